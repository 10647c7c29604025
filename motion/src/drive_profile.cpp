// Reading and validating drive profiles (see drive_profile.hpp).
#include "motion/drive_profile.hpp"

#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "config/reader.hpp"
#include "motion/errors.hpp"

namespace motion {
namespace {

using config::format_number;

constexpr std::int64_t kMaxAddress = 65535;

// "SOURCE: FIELD = VALUE: [PROBLEM; ]expected EXPECTED" for a value in memory.
[[noreturn]] void fail(const DriveProfile& p, const std::string& field, const std::string& value,
                       const std::string& expected, const std::string& problem = "") {
  throw ProfileError(config::error_message(p.source, field, value, expected, problem));
}

// Registers occupied by one field: [first, first + count).
struct Span {
  std::string field;
  int first;
  int count;
};

std::string range(int first, int count) {
  return std::to_string(first) + ".." + std::to_string(first + count - 1);
}

void check_no_overlap(const DriveProfile& p, const std::vector<Span>& spans) {
  for (const Span& s : spans) {
    if (s.first < 0 || s.first + s.count - 1 > kMaxAddress) {
      fail(p, s.field, std::to_string(s.first),
           "an address whose " + std::to_string(s.count) + " register(s) fit in 0..65535");
    }
  }
  for (size_t i = 0; i < spans.size(); ++i) {
    for (size_t j = i + 1; j < spans.size(); ++j) {
      const Span& a = spans[i];
      const Span& b = spans[j];
      if (a.first < b.first + b.count && b.first < a.first + a.count) {
        fail(p, b.field, std::to_string(b.first),
             "registers that no other field of the same table uses",
             "registers " + range(b.first, b.count) + " overlap " + a.field + " (" +
                 range(a.first, a.count) + ")");
      }
    }
  }
}

void check_link_and_units(const DriveProfile& p) {
  if (!(p.unit_id >= 1 && p.unit_id <= 247) && p.unit_id != 255) {
    fail(p, "link.unit_id", std::to_string(p.unit_id), "a unit id 1..247, or 255");
  }
  if (!(p.counts_per_mm > 0) || !std::isfinite(p.counts_per_mm)) {
    fail(p, "units.counts_per_mm", format_number(p.counts_per_mm), "a finite number > 0");
  }
  if (!(p.speed_units_per_mm_s > 0) || !std::isfinite(p.speed_units_per_mm_s)) {
    fail(p, "units.speed_units_per_mm_s", format_number(p.speed_units_per_mm_s),
         "a finite number > 0");
  }
}

// Writes and feedback in their tables: each field's registers fit, and no two
// fields of one table share a register.
void check_registers(const DriveProfile& p) {
  const RegisterMap& r = p.registers;
  const int w = p.position_registers();
  std::vector<Span> holding = {{"registers.target_x", r.target_x, w},
                               {"registers.target_y", r.target_y, w},
                               {"registers.speed", r.speed, 1},
                               {"registers.command", r.command, 1}};
  std::vector<Span> feedback = {{"registers.actual_x", r.actual_x, w},
                                {"registers.actual_y", r.actual_y, w},
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
  std::vector<std::pair<std::string, int>> bits = {
      {"status_bits.homed", b.homed},
      {"status_bits.moving", b.moving},
      {"status_bits.in_position", b.in_position},
      {"status_bits.alarm", b.alarm},
      {"status_bits.emergency_stop", b.emergency_stop}};
  if (p.protocol.ack_bit >= 0) bits.push_back({"handshake.ack_bit", p.protocol.ack_bit});
  if (p.protocol.servo_ready_bit >= 0) {
    bits.push_back({"handshake.servo_ready_bit", p.protocol.servo_ready_bit});
  }
  for (size_t i = 0; i < bits.size(); ++i) {
    const auto& [field, bit] = bits[i];
    if (bit < 0 || bit > 15) fail(p, field, std::to_string(bit), "a bit of a register (0..15)");
    for (size_t j = 0; j < i; ++j) {
      if (bit == bits[j].second) {
        fail(p, field, std::to_string(bit), "a bit that no other status uses",
             "bit " + std::to_string(bit) + " is also " + bits[j].first);
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
  const CommandProtocol& h = p.protocol;
  for (size_t i = 0; i < codes.size(); ++i) {
    const auto& [field, code] = codes[i];
    if (code == 0 && h.handshake != CommandHandshake::kKept) {
      fail(p, field, "0", "a code other than 0",
           "0 is the cleared command register of handshake.command = \"" +
               std::string(h.handshake == CommandHandshake::kPulse ? "pulse" : "self_clearing") +
               "\"");
    }
    if ((code & h.servo_on) != 0) {
      fail(p, field, std::to_string(code),
           "a code sharing no bit with handshake.servo_on (" + std::to_string(h.servo_on) + ")",
           "the servo-on bits are kept set in every command");
    }
    for (size_t j = 0; j < i; ++j) {
      if (code == codes[j].second) {
        fail(p, field, std::to_string(code), "a code that no other command uses",
             "code " + std::to_string(code) + " is also " + codes[j].first);
      }
    }
  }
}

// Speeds that the speed register holds, and a tolerance the encoder can meet.
void check_speeds_and_tolerance(const DriveProfile& p) {
  if (!(p.max_speed_mm_s > 0)) {
    fail(p, "motion.max_speed_mm_s", format_number(p.max_speed_mm_s), "a speed > 0 mm/s");
  }
  if (!(p.default_speed_mm_s > 0) || p.default_speed_mm_s > p.max_speed_mm_s) {
    fail(p, "motion.default_speed_mm_s", format_number(p.default_speed_mm_s),
         "a speed in (0, max_speed_mm_s = " + format_number(p.max_speed_mm_s) + "] mm/s");
  }
  if (std::lround(p.max_speed_mm_s * p.speed_units_per_mm_s) > 65535) {
    fail(p, "motion.max_speed_mm_s", format_number(p.max_speed_mm_s),
         "a speed of at most 65535 speed units (" + format_number(65535 / p.speed_units_per_mm_s) +
             " mm/s)",
         "it does not fit in one 16-bit speed register");
  }
  if (!(p.position_tolerance_mm * p.counts_per_mm >= 1.0)) {
    fail(p, "motion.position_tolerance_mm", format_number(p.position_tolerance_mm),
         "a tolerance of at least one count (" + format_number(1.0 / p.counts_per_mm) + " mm)",
         "finer than one count, the bench could never settle");
  }
}

void check_handshake(const DriveProfile& p) {
  const CommandProtocol& h = p.protocol;
  if (h.servo_on != 0 && h.servo_ready_bit < 0) {
    throw ProfileError(p.source +
                       ": handshake.servo_ready_bit: missing; expected the status bit (0..15) "
                       "the drive sets once the servo is on, with handshake.servo_on");
  }
  if (h.servo_on == 0 && h.servo_ready_bit >= 0) {
    fail(p, "handshake.servo_ready_bit", std::to_string(h.servo_ready_bit),
         "no servo_ready_bit without handshake.servo_on", "there is no servo-on to wait for");
  }
  if (h.ack_bit >= 0 && h.handshake != CommandHandshake::kPulse) {
    fail(p, "handshake.ack_bit", std::to_string(h.ack_bit),
         "an ack_bit only with handshake.command = \"pulse\"");
  }
}

// Soft limits that fit the position registers, are not empty and hold home.
void check_soft_limits(const DriveProfile& p) {
  const SoftLimits& s = p.soft_limits;
  const double max_counts = p.position_bits == 16 ? std::numeric_limits<std::int16_t>::max() - 1.0
                                                  : std::numeric_limits<std::int32_t>::max() - 1.0;
  for (auto [name, v] : {std::pair<const char*, double>{"soft_limits.x_min_mm", s.x_min_mm},
                         {"soft_limits.x_max_mm", s.x_max_mm},
                         {"soft_limits.y_min_mm", s.y_min_mm},
                         {"soft_limits.y_max_mm", s.y_max_mm}}) {
    const double counts = v * p.counts_per_mm;
    if (!std::isfinite(v) || std::fabs(counts) > max_counts) {
      fail(p, name, format_number(v),
           "a limit that fits in a signed " + std::to_string(p.position_bits) +
               "-bit position register (|limit| <= " + format_number(max_counts / p.counts_per_mm) +
               " mm at units.counts_per_mm = " + format_number(p.counts_per_mm) + ")");
    }
  }
  if (!(s.x_min_mm < s.x_max_mm)) {
    fail(p, "soft_limits.x_max_mm", format_number(s.x_max_mm),
         "a limit > soft_limits.x_min_mm (" + format_number(s.x_min_mm) + ")");
  }
  if (!(s.y_min_mm < s.y_max_mm)) {
    fail(p, "soft_limits.y_max_mm", format_number(s.y_max_mm),
         "a limit > soft_limits.y_min_mm (" + format_number(s.y_min_mm) + ")");
  }
  if (!s.contains(p.home_x_mm, p.home_y_mm)) {
    const std::string field = s.contains(p.home_x_mm, s.y_min_mm) ? "y" : "x";
    fail(p, "motion.home_" + field + "_mm", format_number(field == "x" ? p.home_x_mm : p.home_y_mm),
         "a home inside the soft limits x " + format_number(s.x_min_mm) + ".." +
             format_number(s.x_max_mm) + " mm, y " + format_number(s.y_min_mm) + ".." +
             format_number(s.y_max_mm) + " mm");
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
    if (v <= 0) fail(p, name, std::to_string(v), "a time > 0 ms");
  }
  if (t.settle_time_ms < 0) {
    fail(p, "motion.settle_time_ms", std::to_string(t.settle_time_ms), "a time >= 0 ms");
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

void DriveProfile::encode_position(std::int32_t counts, std::uint16_t out[2]) const {
  if (position_bits == 16) {
    out[0] = static_cast<std::uint16_t>(static_cast<std::int16_t>(counts));
    return;
  }
  encode_int32(counts, word_order, out);
}

std::int32_t DriveProfile::decode_position(const std::uint16_t in[2]) const {
  if (position_bits == 16) return static_cast<std::int16_t>(in[0]);
  return decode_int32(in, word_order);
}

std::int32_t decode_int32(const std::uint16_t in[2], WordOrder order) {
  const std::uint32_t high = order == WordOrder::kHighFirst ? in[0] : in[1];
  const std::uint32_t low = order == WordOrder::kHighFirst ? in[1] : in[0];
  return static_cast<std::int32_t>((high << 16) | low);
}

void validate(const DriveProfile& p) {
  check_link_and_units(p);
  check_registers(p);
  check_status_bits(p);
  check_handshake(p);
  check_command_codes(p);
  check_speeds_and_tolerance(p);
  check_soft_limits(p);
  check_timing(p);
}

namespace {

void read_link(config::Table link, DriveProfile* p) {
  p->unit_id = static_cast<int>(link.integer("unit_id", 0, 255));
  p->word_order = link.choice("word_order", {"high_first", "low_first"}) == "high_first"
                      ? WordOrder::kHighFirst
                      : WordOrder::kLowFirst;
  p->timing.response_timeout_ms = static_cast<int>(link.integer("response_timeout_ms", 1, 60000));
  p->timing.reconnect_timeout_ms =
      static_cast<int>(link.integer("reconnect_timeout_ms", 1, 3600000));
  link.reject_unknown();
}

void read_units(config::Table units, DriveProfile* p) {
  p->counts_per_mm = units.number("counts_per_mm", config::positive());
  p->speed_units_per_mm_s = units.number("speed_units_per_mm_s", config::positive());
  const std::int64_t bits = units.integer_or("position_bits", 32, 16, 32, "16 or 32");
  if (bits != 16 && bits != 32) units.fail("position_bits", "16 or 32");
  p->position_bits = static_cast<int>(bits);
  units.reject_unknown();
}

void read_registers(config::Table regs, RegisterMap* r) {
  auto addr = [&](const char* key) { return static_cast<int>(regs.integer(key, 0, kMaxAddress)); };
  r->target_x = addr("target_x");
  r->target_y = addr("target_y");
  r->speed = addr("speed");
  r->command = addr("command");
  r->feedback = regs.choice("feedback", {"input", "holding"}) == "input" ? RegisterTable::kInput
                                                                         : RegisterTable::kHolding;
  r->actual_x = addr("actual_x");
  r->actual_y = addr("actual_y");
  r->status = addr("status");
  r->alarm = addr("alarm");
  regs.reject_unknown();
}

void read_status_bits(config::Table bits, StatusBits* b) {
  auto bit = [&](const char* key) { return static_cast<int>(bits.integer(key, 0, 15)); };
  b->homed = bit("homed");
  b->moving = bit("moving");
  b->in_position = bit("in_position");
  b->alarm = bit("alarm");
  b->emergency_stop = bit("emergency_stop");
  bits.reject_unknown();
}

void read_commands(config::Table cmds, CommandCodes* c) {
  auto code = [&](const char* key) {
    return static_cast<std::uint16_t>(cmds.integer(key, 0, 65535));
  };
  c->move_absolute = code("move_absolute");
  c->home = code("home");
  c->stop = code("stop");
  c->reset_alarm = code("reset_alarm");
  cmds.reject_unknown();
}

void read_motion(config::Table mot, DriveProfile* p) {
  p->default_speed_mm_s = mot.number("default_speed_mm_s", config::positive());
  p->max_speed_mm_s = mot.number("max_speed_mm_s", config::positive());
  p->position_tolerance_mm = mot.number("position_tolerance_mm", config::positive());
  p->home_x_mm = mot.number("home_x_mm");
  p->home_y_mm = mot.number("home_y_mm");
  p->timing.poll_interval_ms = static_cast<int>(mot.integer("poll_interval_ms", 1, 10000));
  p->timing.settle_time_ms = static_cast<int>(mot.integer("settle_time_ms", 0, 600000));
  p->timing.settle_timeout_ms = static_cast<int>(mot.integer("settle_timeout_ms", 1, 3600000));
  p->timing.home_timeout_ms = static_cast<int>(mot.integer("home_timeout_ms", 1, 3600000));
  mot.reject_unknown();
}

void read_soft_limits(config::Table lim, SoftLimits* s) {
  s->x_min_mm = lim.number("x_min_mm");
  s->x_max_mm = lim.number("x_max_mm");
  s->y_min_mm = lim.number("y_min_mm");
  s->y_max_mm = lim.number("y_max_mm");
  lim.reject_unknown();
}

// [handshake] (optional): the drive's command conventions.
void read_handshake(config::Table h, CommandProtocol* c) {
  const std::string mode = h.choice_or("command", "kept", {"kept", "self_clearing", "pulse"});
  c->handshake = mode == "kept"            ? CommandHandshake::kKept
                 : mode == "self_clearing" ? CommandHandshake::kSelfClearing
                                           : CommandHandshake::kPulse;
  c->accept_timeout_ms =
      static_cast<int>(h.integer_or("accept_timeout_ms", c->accept_timeout_ms, 1, 600000));
  if (h.has("ack_bit")) c->ack_bit = static_cast<int>(h.integer("ack_bit", 0, 15));
  c->pulse_ms = static_cast<int>(h.integer_or("pulse_ms", c->pulse_ms, 1, 10000));
  c->servo_on = static_cast<std::uint16_t>(h.integer_or("servo_on", 0, 0, 65535));
  if (h.has("servo_ready_bit")) {
    c->servo_ready_bit = static_cast<int>(h.integer("servo_ready_bit", 0, 15));
  }
  c->reset_pulse = h.choice_or("reset", "command", {"command", "pulse"}) == "pulse";
  h.reject_unknown();
}

// [alarms]: code = "meaning", codes in decimal or hex as drive manuals write them.
void read_alarms(config::Table alarms, std::map<int, std::string>* meanings) {
  for (const auto& [code, meaning] :
       alarms.strings_by_code(1, 65535, "an alarm code", "the alarm's meaning, a string")) {
    (*meanings)[static_cast<int>(code)] = meaning;
  }
}

DriveProfile read_profile(const config::Document& file) {
  config::Table root = file.root();
  DriveProfile p;
  p.source = file.source();
  p.name = root.string("name", "the profile's name, a string");
  read_link(root.table("link"), &p);
  read_units(root.table("units"), &p);
  read_registers(root.table("registers"), &p.registers);
  read_status_bits(root.table("status_bits"), &p.status_bits);
  read_commands(root.table("commands"), &p.commands);
  read_motion(root.table("motion"), &p);
  read_soft_limits(root.table("soft_limits"), &p.soft_limits);
  read_handshake(root.optional_table("handshake"), &p.protocol);
  read_alarms(root.optional_table("alarms"), &p.alarm_meanings);
  root.ignore("sim");  // the simulated bench's own table (sim/bench/config.hpp)
  root.reject_unknown();
  validate(p);
  return p;
}

}  // namespace

DriveProfile parse_drive_profile(std::string_view text, const std::string& source) {
  return read_profile(
      config::Document::parse<ProfileError>(std::string(text), source, "the drive profile"));
}

DriveProfile load_drive_profile(const std::string& path) {
  return read_profile(config::Document::read<ProfileError>(path, "the drive profile"));
}

}  // namespace motion
