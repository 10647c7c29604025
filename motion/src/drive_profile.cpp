// Reading and validating drive profiles (see drive_profile.hpp).
#include "motion/drive_profile.hpp"

#include <algorithm>
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

// The name in the file of a field of `p` named as in a controller's profile:
// for a single-axis drive, its own tables are under [x] or [y] and name the
// axis once ("registers.target_x" -> "y.registers.target"), while [motion]
// and [soft_limits] are the bench's, with the axis's keys.
std::string field_name(const DriveProfile& p, const std::string& field) {
  if (!p.single_axis()) return field;
  const std::string a(1, p.axis);
  for (const char* shared : {"soft_limits.x_", "motion.home_x"}) {
    const std::string prefix(shared);
    if (field.rfind(prefix, 0) == 0) {
      return prefix.substr(0, prefix.size() - 2) + (prefix.back() == '_' ? a + "_" : "_" + a) +
             field.substr(prefix.size());
    }
  }
  if (field.rfind("motion.", 0) == 0) return field;
  std::string own = field;
  if (own.size() > 2 && own.compare(own.size() - 2, 2, "_x") == 0) own.resize(own.size() - 2);
  return a + "." + own;
}

// "SOURCE: FIELD = VALUE: [PROBLEM; ]expected EXPECTED" for a value in memory.
[[noreturn]] void fail(const DriveProfile& p, const std::string& field, const std::string& value,
                       const std::string& expected, const std::string& problem = "") {
  throw ProfileError(
      config::error_message(p.source, field_name(p, field), value, expected, problem));
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

// Spans name their fields as in the file already (field_name).
void check_no_overlap(const DriveProfile& p, const std::vector<Span>& spans) {
  auto fail = [&p](const std::string& field, const std::string& value, const std::string& expected,
                   const std::string& problem = "") {
    throw ProfileError(config::error_message(p.source, field, value, expected, problem));
  };
  for (const Span& s : spans) {
    if (s.first < 0 || s.first + s.count - 1 > kMaxAddress) {
      fail(s.field, std::to_string(s.first),
           "an address whose " + std::to_string(s.count) + " register(s) fit in 0..65535");
    }
  }
  for (size_t i = 0; i < spans.size(); ++i) {
    for (size_t j = i + 1; j < spans.size(); ++j) {
      const Span& a = spans[i];
      const Span& b = spans[j];
      if (a.first < b.first + b.count && b.first < a.first + a.count) {
        fail(b.field, std::to_string(b.first),
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
                               {"registers.speed", r.speed, 1},
                               {"registers.command", r.command, 1}};
  std::vector<Span> feedback = {{"registers.actual_x", r.actual_x, w},
                                {"registers.status", r.status, 1},
                                {"registers.alarm", r.alarm, 1}};
  if (r.moving_status >= 0) feedback.push_back({"registers.moving_status", r.moving_status, 1});
  if (!p.single_axis()) {
    holding.insert(holding.begin() + 1, {"registers.target_y", r.target_y, w});
    feedback.insert(feedback.begin() + 1, {"registers.actual_y", r.actual_y, w});
  }
  for (Span& s : holding)
    s.field = field_name(p, s.field);
  for (Span& s : feedback)
    s.field = field_name(p, s.field);
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
  // With registers.moving_status, the moving bit is of another register.
  const bool moving_apart = p.registers.moving_status >= 0;
  for (size_t i = 0; i < bits.size(); ++i) {
    const auto& [field, bit] = bits[i];
    if (bit < 0 || bit > 15) fail(p, field, std::to_string(bit), "a bit of a register (0..15)");
    for (size_t j = 0; j < i; ++j) {
      if (moving_apart && (i == 1 || j == 1)) continue;  // bits[1] is the moving bit
      if (bit == bits[j].second) {
        fail(p, field, std::to_string(bit), "a bit that no other status uses",
             "bit " + std::to_string(bit) + " is also " + field_name(p, bits[j].first));
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
           "a code sharing no bit with " + field_name(p, "handshake.servo_on") + " (" +
               std::to_string(h.servo_on) + ")",
           "the servo-on bits are kept set in every command");
    }
    for (size_t j = 0; j < i; ++j) {
      if (code == codes[j].second) {
        fail(p, field, std::to_string(code), "a code that no other command uses",
             "code " + std::to_string(code) + " is also " + field_name(p, codes[j].first));
      }
    }
  }
}

void check_speeds(const DriveProfile& p) {
  if (!(p.max_speed_mm_s > 0)) {
    fail(p, "motion.max_speed_mm_s", format_number(p.max_speed_mm_s), "a speed > 0 mm/s");
  }
  if (!(p.default_speed_mm_s > 0) || p.default_speed_mm_s > p.max_speed_mm_s) {
    fail(p, "motion.default_speed_mm_s", format_number(p.default_speed_mm_s),
         "a speed in (0, max_speed_mm_s = " + format_number(p.max_speed_mm_s) + "] mm/s");
  }
}

// Speeds that the speed register holds, and a tolerance the encoder can meet.
void check_speeds_and_tolerance(const DriveProfile& p) {
  check_speeds(p);
  const std::string per_drive =
      p.single_axis() ? std::string(" of the ") + p.axis + " axis drive" : "";
  if (std::lround(p.max_speed_mm_s * p.speed_units_per_mm_s) > 65535) {
    fail(p, "motion.max_speed_mm_s", format_number(p.max_speed_mm_s),
         "a speed of at most 65535 speed units (" + format_number(65535 / p.speed_units_per_mm_s) +
             " mm/s)",
         "it does not fit in one 16-bit speed register" + per_drive);
  }
  if (!(p.position_tolerance_mm * p.counts_per_mm >= 1.0)) {
    fail(p, "motion.position_tolerance_mm", format_number(p.position_tolerance_mm),
         "a tolerance of at least one count" + per_drive + " (" +
             format_number(1.0 / p.counts_per_mm) + " mm)",
         "finer than one count, the bench could never settle");
  }
}

void check_handshake(const DriveProfile& p) {
  const CommandProtocol& h = p.protocol;
  if (h.servo_on != 0 && h.servo_ready_bit < 0) {
    throw ProfileError(p.source + ": " + field_name(p, "handshake.servo_ready_bit") +
                       ": missing; expected the status bit (0..15) the drive sets once the servo "
                       "is on, with " +
                       field_name(p, "handshake.servo_on"));
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
  std::vector<std::pair<const char*, double>> limits = {{"soft_limits.x_min_mm", s.x_min_mm},
                                                        {"soft_limits.x_max_mm", s.x_max_mm}};
  if (!p.single_axis()) {
    limits.push_back({"soft_limits.y_min_mm", s.y_min_mm});
    limits.push_back({"soft_limits.y_max_mm", s.y_max_mm});
  }
  // A bench of two drives: each drive checks that its axis fits its registers.
  if (p.axis_drives) limits.clear();
  for (auto [name, v] : limits) {
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
  if (p.single_axis()) {
    if (!(p.home_x_mm >= s.x_min_mm && p.home_x_mm <= s.x_max_mm)) {
      fail(p, "motion.home_x_mm", format_number(p.home_x_mm),
           "a home inside the soft limits " + format_number(s.x_min_mm) + ".." +
               format_number(s.x_max_mm) + " mm");
    }
    return;
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

std::string SoftLimits::refusal(double x_mm, double y_mm, const std::string& source) const {
  return "move to (" + format_number(x_mm) + ", " + format_number(y_mm) +
         ") mm refused, nothing sent: outside the soft limits x [" + format_number(x_min_mm) +
         ", " + format_number(x_max_mm) + "], y [" + format_number(y_min_mm) + ", " +
         format_number(y_max_mm) + "] mm of " + source;
}

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
  if (p.axis_drives) {
    // A bench of two drives: its shared [motion] and [soft_limits] here, and
    // each drive with its own link, units and registers.
    check_speeds(p);
    check_soft_limits(p);
    check_timing(p);
    for (const AxisDrive* d : {&p.axis_drives->x, &p.axis_drives->y}) {
      if (d->drive.axis != (d == &p.axis_drives->x ? 'x' : 'y')) {
        throw ProfileError(p.source + ": the drive of the " + (d == &p.axis_drives->x ? "x" : "y") +
                           " axis is marked as the drive of axis '" + d->drive.axis +
                           "'; expected its own axis");
      }
      validate(d->drive);
    }
    return;
  }
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
  if (regs.has("moving_status")) r->moving_status = addr("moving_status");
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

// A single-axis drive's [registers]: one target and one read-back.
void read_axis_registers(config::Table regs, RegisterMap* r) {
  auto addr = [&](const char* key) { return static_cast<int>(regs.integer(key, 0, kMaxAddress)); };
  r->target_x = addr("target");
  r->speed = addr("speed");
  r->command = addr("command");
  r->feedback = regs.choice("feedback", {"input", "holding"}) == "input" ? RegisterTable::kInput
                                                                         : RegisterTable::kHolding;
  r->actual_x = addr("actual");
  r->status = addr("status");
  r->alarm = addr("alarm");
  if (regs.has("moving_status")) r->moving_status = addr("moving_status");
  regs.reject_unknown();
}

// The tables of one drive, at the top of a controller's profile or in the
// [x] / [y] table of a bench of two drives.
void read_drive_tables(config::Table& t, DriveProfile* p) {
  read_link(t.table("link"), p);
  read_units(t.table("units"), p);
  if (p->single_axis()) {
    read_axis_registers(t.table("registers"), &p->registers);
  } else {
    read_registers(t.table("registers"), &p->registers);
  }
  read_status_bits(t.table("status_bits"), &p->status_bits);
  read_commands(t.table("commands"), &p->commands);
}

// The optional tables of one drive: its command conventions and alarm texts.
void read_drive_options(config::Table& t, DriveProfile* p) {
  read_handshake(t.optional_table("handshake"), &p->protocol);
  read_alarms(t.optional_table("alarms"), &p->alarm_meanings);
}

// [x] or [y] of a bench of two drives: the drive's own tables and its
// optional link of its own.
AxisDrive read_axis_drive(config::Table t, char axis) {
  AxisDrive d;
  d.drive.axis = axis;
  read_drive_tables(t, &d.drive);
  read_drive_options(t, &d.drive);
  if (t.has("url")) {
    const std::string url = t.string("url", "a bench URL");
    try {
      d.url = BenchUrl::parse(url);
    } catch (const ProfileError& e) {
      t.fail("url", "modbus-tcp://HOST:PORT[?unit=N] or modbus-rtu:///dev/DEVICE?baud=...",
             e.what());
    }
  }
  t.reject_unknown();
  return d;
}

// What a drive of a two-drive bench takes from the bench: its axis's soft
// limits and home, and the shared [motion]; it keeps its own link timeouts.
void share_bench_motion(const DriveProfile& bench, DriveProfile* d) {
  const bool x = d->axis == 'x';
  d->name = bench.name + ": " + (x ? "X" : "Y") + " axis drive";
  d->source = bench.source;
  d->default_speed_mm_s = bench.default_speed_mm_s;
  d->max_speed_mm_s = bench.max_speed_mm_s;
  d->position_tolerance_mm = bench.position_tolerance_mm;
  const Timing own = d->timing;
  d->timing = bench.timing;
  d->timing.response_timeout_ms = own.response_timeout_ms;
  d->timing.reconnect_timeout_ms = own.reconnect_timeout_ms;
  d->soft_limits = SoftLimits{};
  d->soft_limits.x_min_mm = x ? bench.soft_limits.x_min_mm : bench.soft_limits.y_min_mm;
  d->soft_limits.x_max_mm = x ? bench.soft_limits.x_max_mm : bench.soft_limits.y_max_mm;
  d->home_x_mm = x ? bench.home_x_mm : bench.home_y_mm;
  d->home_y_mm = 0;
}

DriveProfile read_profile(const config::Document& file) {
  config::Table root = file.root();
  DriveProfile p;
  p.source = file.source();
  p.name = root.string("name", "the profile's name, a string");
  const bool two_drives = root.has("x") || root.has("y");
  std::shared_ptr<AxisDrives> drives;
  if (two_drives) {
    drives = std::make_shared<AxisDrives>();
    drives->x = read_axis_drive(root.table("x"), 'x');
    drives->y = read_axis_drive(root.table("y"), 'y');
  } else {
    read_drive_tables(root, &p);
  }
  read_motion(root.table("motion"), &p);
  read_soft_limits(root.table("soft_limits"), &p.soft_limits);
  if (!two_drives) read_drive_options(root, &p);
  root.ignore("sim");  // the simulated bench's own table (sim/bench/config.hpp)
  if (two_drives) {
    root.reject_unknown(
        "name, [x], [y], [motion] and [soft_limits] (a bench of two single-axis drives: each "
        "drive's [link], [units], [registers], [status_bits], [commands], [handshake] and "
        "[alarms] go inside its [x] or [y] table)");
    for (AxisDrive* d : {&drives->x, &drives->y})
      share_bench_motion(p, &d->drive);
    // The bench's own link fields: the slower of the two drives'.
    p.timing.response_timeout_ms = std::max(drives->x.drive.timing.response_timeout_ms,
                                            drives->y.drive.timing.response_timeout_ms);
    p.timing.reconnect_timeout_ms = std::max(drives->x.drive.timing.reconnect_timeout_ms,
                                             drives->y.drive.timing.reconnect_timeout_ms);
    p.axis_drives = std::move(drives);
  } else {
    root.reject_unknown();
  }
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
