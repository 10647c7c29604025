// Reading and validating drive profiles (see drive_profile.hpp).
#include "motion/drive_profile.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <limits>
#include <set>
#include <utility>
#include <vector>

#include "motion/errors.hpp"
#include "motion/toml_reader.hpp"

namespace motion {
namespace {

using TableReader = TomlTableReader;

constexpr std::int64_t kMaxAddress = 65535;

// Registers occupied by one field: [first, first + count).
struct Span {
  std::string field;
  int first;
  int count;
};

void check_no_overlap(const DriveProfile& p, std::vector<Span> spans) {
  for (const Span& s : spans) {
    if (s.first < 0 || s.first + s.count - 1 > kMaxAddress) {
      throw ProfileError(p.source + ": " + s.field + ": address " + std::to_string(s.first) +
                         " does not fit in 0..65535 with its " + std::to_string(s.count) +
                         " register(s)");
    }
  }
  for (size_t i = 0; i < spans.size(); ++i) {
    for (size_t j = i + 1; j < spans.size(); ++j) {
      const Span& a = spans[i];
      const Span& b = spans[j];
      if (a.first < b.first + b.count && b.first < a.first + a.count) {
        throw ProfileError(p.source + ": " + b.field + ": registers " + std::to_string(b.first) +
                           ".." + std::to_string(b.first + b.count - 1) + " overlap " + a.field +
                           " (" + std::to_string(a.first) + ".." +
                           std::to_string(a.first + a.count - 1) + ")");
      }
    }
  }
}

}  // namespace

std::int32_t DriveProfile::to_counts(double mm) const {
  return static_cast<std::int32_t>(std::lround(mm * counts_per_mm));
}

std::string DriveProfile::alarm_meaning(int code) const {
  auto it = alarm_meanings.find(code);
  return it != alarm_meanings.end() ? it->second : "unknown alarm code " + std::to_string(code);
}

void encode_int32(std::int32_t value, WordOrder order, std::uint16_t out[2]) {
  const auto u = static_cast<std::uint32_t>(value);
  const auto high = static_cast<std::uint16_t>(u >> 16);
  const auto low = static_cast<std::uint16_t>(u & 0xFFFFu);
  out[0] = order == WordOrder::kHighFirst ? high : low;
  out[1] = order == WordOrder::kHighFirst ? low : high;
}

std::int32_t decode_int32(const std::uint16_t in[2], WordOrder order) {
  const std::uint32_t high = order == WordOrder::kHighFirst ? in[0] : in[1];
  const std::uint32_t low = order == WordOrder::kHighFirst ? in[1] : in[0];
  return static_cast<std::int32_t>((high << 16) | low);
}

namespace {

[[noreturn]] void fail(const DriveProfile& p, const std::string& field, const std::string& what) {
  throw ProfileError(p.source + ": " + field + ": " + what);
}

void check_link_and_units(const DriveProfile& p) {
  if (!(p.unit_id >= 1 && p.unit_id <= 247) && p.unit_id != 255) {
    fail(p, "link.unit_id", std::to_string(p.unit_id) + " is not a unit id (1..247, or 255)");
  }
  if (!(p.counts_per_mm > 0) || !std::isfinite(p.counts_per_mm)) {
    fail(p, "units.counts_per_mm", "must be a finite number > 0");
  }
  if (!(p.speed_units_per_mm_s > 0)) fail(p, "units.speed_units_per_mm_s", "must be > 0");
}

// Writes and feedback in their tables: each field's registers fit, and no two
// fields of one table share a register.
void check_registers(const DriveProfile& p) {
  const RegisterMap& r = p.registers;
  std::vector<Span> holding = {{"registers.target_x", r.target_x, 2},
                               {"registers.target_y", r.target_y, 2},
                               {"registers.speed", r.speed, 1},
                               {"registers.command", r.command, 1}};
  std::vector<Span> feedback = {{"registers.actual_x", r.actual_x, 2},
                                {"registers.actual_y", r.actual_y, 2},
                                {"registers.status", r.status, 1},
                                {"registers.alarm", r.alarm, 1}};
  if (r.feedback == RegisterTable::kHolding) {
    holding.insert(holding.end(), feedback.begin(), feedback.end());
    check_no_overlap(p, holding);
  } else {
    check_no_overlap(p, holding);
    check_no_overlap(p, feedback);
  }
}

void check_status_bits(const DriveProfile& p) {
  const StatusBits& b = p.status_bits;
  const std::vector<std::pair<std::string, int>> bits = {
      {"status_bits.homed", b.homed},
      {"status_bits.moving", b.moving},
      {"status_bits.in_position", b.in_position},
      {"status_bits.alarm", b.alarm},
      {"status_bits.emergency_stop", b.emergency_stop}};
  for (size_t i = 0; i < bits.size(); ++i) {
    if (bits[i].second < 0 || bits[i].second > 15) {
      fail(p, bits[i].first,
           std::to_string(bits[i].second) + " is not a bit of a register (0..15)");
    }
    for (size_t j = 0; j < i; ++j) {
      if (bits[i].second == bits[j].second) {
        fail(p, bits[i].first,
             "bit " + std::to_string(bits[i].second) + " is also " + bits[j].first);
      }
    }
  }
}

void check_command_codes(const DriveProfile& p) {
  const CommandCodes& c = p.commands;
  const std::vector<std::pair<std::string, int>> codes = {
      {"commands.move_absolute", c.move_absolute},
      {"commands.home", c.home},
      {"commands.stop", c.stop},
      {"commands.reset_alarm", c.reset_alarm}};
  for (size_t i = 0; i < codes.size(); ++i) {
    for (size_t j = 0; j < i; ++j) {
      if (codes[i].second == codes[j].second) {
        fail(p, codes[i].first,
             "code " + std::to_string(codes[i].second) + " is also " + codes[j].first);
      }
    }
  }
}

// Speeds that the speed register holds, and a tolerance the encoder can meet.
void check_speeds_and_tolerance(const DriveProfile& p) {
  if (!(p.max_speed_mm_s > 0)) fail(p, "motion.max_speed_mm_s", "must be > 0");
  if (!(p.default_speed_mm_s > 0) || p.default_speed_mm_s > p.max_speed_mm_s) {
    fail(p, "motion.default_speed_mm_s",
         std::to_string(p.default_speed_mm_s) +
             " must be in (0, max_speed_mm_s = " + std::to_string(p.max_speed_mm_s) + "]");
  }
  if (std::lround(p.max_speed_mm_s * p.speed_units_per_mm_s) > 65535) {
    fail(p, "motion.max_speed_mm_s", "does not fit in one 16-bit speed register");
  }
  if (!(p.position_tolerance_mm * p.counts_per_mm >= 1.0)) {
    fail(p, "motion.position_tolerance_mm",
         std::to_string(p.position_tolerance_mm) + " mm is finer than one count (" +
             std::to_string(1.0 / p.counts_per_mm) + " mm): the bench could never settle");
  }
}

// Soft limits that fit the position registers, are not empty and hold home.
void check_soft_limits(const DriveProfile& p) {
  const SoftLimits& s = p.soft_limits;
  for (auto [name, v] : {std::pair<const char*, double>{"soft_limits.x_min_mm", s.x_min_mm},
                         {"soft_limits.x_max_mm", s.x_max_mm},
                         {"soft_limits.y_min_mm", s.y_min_mm},
                         {"soft_limits.y_max_mm", s.y_max_mm}}) {
    const double counts = v * p.counts_per_mm;
    if (!std::isfinite(v) || std::fabs(counts) > std::numeric_limits<std::int32_t>::max() - 1.0) {
      fail(p, name, std::to_string(v) + " mm does not fit in a signed 32-bit position register");
    }
  }
  if (!(s.x_min_mm < s.x_max_mm)) fail(p, "soft_limits.x_max_mm", "must be > x_min_mm");
  if (!(s.y_min_mm < s.y_max_mm)) fail(p, "soft_limits.y_max_mm", "must be > y_min_mm");
  if (!s.contains(p.home_x_mm, p.home_y_mm)) {
    fail(p, "motion.home_x_mm",
         "home (" + std::to_string(p.home_x_mm) + ", " + std::to_string(p.home_y_mm) +
             ") mm lies outside the soft limits");
  }
}

void check_timing(const DriveProfile& p) {
  const Timing& t = p.timing;
  for (auto [name, v] :
       {std::pair<const char*, int>{"link.response_timeout_ms", t.response_timeout_ms},
        {"link.reconnect_timeout_ms", t.reconnect_timeout_ms},
        {"motion.poll_interval_ms", t.poll_interval_ms},
        {"motion.settle_timeout_ms", t.settle_timeout_ms},
        {"motion.home_timeout_ms", t.home_timeout_ms}}) {
    if (v <= 0) fail(p, name, std::to_string(v) + " must be > 0");
  }
  if (t.settle_time_ms < 0) fail(p, "motion.settle_time_ms", "must be >= 0");
}

}  // namespace

void validate(const DriveProfile& p) {
  check_link_and_units(p);
  check_registers(p);
  check_status_bits(p);
  check_command_codes(p);
  check_speeds_and_tolerance(p);
  check_soft_limits(p);
  check_timing(p);
}

namespace {

void read_link(const toml::table& root, const std::string& source, DriveProfile* p) {
  TableReader link(root, source, "link");
  p->unit_id = static_cast<int>(link.integer("unit_id", 0, 255));
  const std::string order = link.string("word_order");
  if (order == "high_first") {
    p->word_order = WordOrder::kHighFirst;
  } else if (order == "low_first") {
    p->word_order = WordOrder::kLowFirst;
  } else {
    link.fail("word_order", "\"" + order + "\" is not \"high_first\" or \"low_first\"");
  }
  p->timing.response_timeout_ms = static_cast<int>(link.integer("response_timeout_ms", 1, 60000));
  p->timing.reconnect_timeout_ms =
      static_cast<int>(link.integer("reconnect_timeout_ms", 1, 3600000));
  link.reject_unknown();
}

void read_units(const toml::table& root, const std::string& source, DriveProfile* p) {
  TableReader units(root, source, "units");
  p->counts_per_mm = units.positive("counts_per_mm");
  p->speed_units_per_mm_s = units.positive("speed_units_per_mm_s");
  units.reject_unknown();
}

void read_registers(const toml::table& root, const std::string& source, RegisterMap* r) {
  TableReader regs(root, source, "registers");
  auto addr = [&](const char* key) { return static_cast<int>(regs.integer(key, 0, kMaxAddress)); };
  r->target_x = addr("target_x");
  r->target_y = addr("target_y");
  r->speed = addr("speed");
  r->command = addr("command");
  const std::string table = regs.string("feedback");
  if (table == "input") {
    r->feedback = RegisterTable::kInput;
  } else if (table == "holding") {
    r->feedback = RegisterTable::kHolding;
  } else {
    regs.fail("feedback", "\"" + table + "\" is not \"input\" or \"holding\"");
  }
  r->actual_x = addr("actual_x");
  r->actual_y = addr("actual_y");
  r->status = addr("status");
  r->alarm = addr("alarm");
  regs.reject_unknown();
}

void read_status_bits(const toml::table& root, const std::string& source, StatusBits* b) {
  TableReader bits(root, source, "status_bits");
  auto bit = [&](const char* key) { return static_cast<int>(bits.integer(key, 0, 15)); };
  b->homed = bit("homed");
  b->moving = bit("moving");
  b->in_position = bit("in_position");
  b->alarm = bit("alarm");
  b->emergency_stop = bit("emergency_stop");
  bits.reject_unknown();
}

void read_commands(const toml::table& root, const std::string& source, CommandCodes* c) {
  TableReader cmds(root, source, "commands");
  auto code = [&](const char* key) {
    return static_cast<std::uint16_t>(cmds.integer(key, 0, 65535));
  };
  c->move_absolute = code("move_absolute");
  c->home = code("home");
  c->stop = code("stop");
  c->reset_alarm = code("reset_alarm");
  cmds.reject_unknown();
}

void read_motion(const toml::table& root, const std::string& source, DriveProfile* p) {
  TableReader mot(root, source, "motion");
  p->default_speed_mm_s = mot.positive("default_speed_mm_s");
  p->max_speed_mm_s = mot.positive("max_speed_mm_s");
  p->position_tolerance_mm = mot.positive("position_tolerance_mm");
  p->home_x_mm = mot.number("home_x_mm");
  p->home_y_mm = mot.number("home_y_mm");
  p->timing.poll_interval_ms = static_cast<int>(mot.integer("poll_interval_ms", 1, 10000));
  p->timing.settle_time_ms = static_cast<int>(mot.integer("settle_time_ms", 0, 600000));
  p->timing.settle_timeout_ms = static_cast<int>(mot.integer("settle_timeout_ms", 1, 3600000));
  p->timing.home_timeout_ms = static_cast<int>(mot.integer("home_timeout_ms", 1, 3600000));
  mot.reject_unknown();
}

void read_soft_limits(const toml::table& root, const std::string& source, SoftLimits* s) {
  TableReader lim(root, source, "soft_limits");
  s->x_min_mm = lim.number("x_min_mm");
  s->x_max_mm = lim.number("x_max_mm");
  s->y_min_mm = lim.number("y_min_mm");
  s->y_max_mm = lim.number("y_max_mm");
  lim.reject_unknown();
}

void read_alarms(const toml::table& root, const std::string& source,
                 std::map<int, std::string>* meanings) {
  const toml::node* alarms = root.get("alarms");
  if (!alarms) return;
  const toml::table* t = alarms->as_table();
  if (!t) throw ProfileError(source + ": alarms: expected a table of code = \"meaning\"");
  for (const auto& [key, value] : *t) {
    const std::string k(key.str());
    char* end = nullptr;
    const long code_value = std::strtol(k.c_str(), &end, 10);
    if (k.empty() || *end != '\0' || code_value < 1 || code_value > 65535) {
      throw ProfileError(source + ": alarms." + k + ": key must be an alarm code 1..65535");
    }
    auto meaning = value.value<std::string>();
    if (!meaning) throw ProfileError(source + ": alarms." + k + ": expected a string");
    (*meanings)[static_cast<int>(code_value)] = *meaning;
  }
}

// Top-level keys: the profile's tables, and [sim] (read by the simulated bench).
void reject_unknown_tables(const toml::table& root, const std::string& source) {
  static const std::set<std::string> kTables = {"name",        "link",     "units",  "registers",
                                                "status_bits", "commands", "motion", "soft_limits",
                                                "alarms",      "sim"};
  for (const auto& [key, value] : root) {
    if (!kTables.count(std::string(key.str()))) {
      throw ProfileError(source + ": " + std::string(key.str()) + ": unknown key (misspelt?)");
    }
  }
}

}  // namespace

DriveProfile parse_drive_profile(std::string_view text, const std::string& source) {
  const toml::table root = parse_toml(text, source);
  DriveProfile p;
  p.source = source;
  TableReader top(root, source, "");
  p.name = top.string("name");
  read_link(root, source, &p);
  read_units(root, source, &p);
  read_registers(root, source, &p.registers);
  read_status_bits(root, source, &p.status_bits);
  read_commands(root, source, &p.commands);
  read_motion(root, source, &p);
  read_soft_limits(root, source, &p.soft_limits);
  read_alarms(root, source, &p.alarm_meanings);
  reject_unknown_tables(root, source);
  validate(p);
  return p;
}

DriveProfile load_drive_profile(const std::string& path) {
  return parse_drive_profile(read_text_file(path, "the drive profile"), path);
}

}  // namespace motion
