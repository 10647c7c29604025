// ModbusBench: moves, settling, read-back verification and the reconnect
// watchdog (see modbus_bench.hpp).
#include "motion/modbus_bench.hpp"

#include <modbus/modbus.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <sstream>
#include <thread>
#include <vector>

#include "config/reader.hpp"
#include "motion/errors.hpp"
#include "settle_watch.hpp"

namespace motion {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// The Modbus PDU limit for one read (function 03/04).
constexpr int kMaxReadRegisters = 125;
// Link failures tolerated within one operation before giving up; each one is
// followed by a full reconnect (with its own timeout and state re-read).
constexpr int kMaxAttempts = 5;
constexpr milliseconds kBackoffFirst{10};
constexpr milliseconds kBackoffMax{500};

}  // namespace

ModbusBench::ModbusBench(const BenchUrl& url, DriveProfile profile)
    : profile_(std::move(profile)),
      link_(url, url.unit.value_or(profile_.unit_id),
            milliseconds(profile_.timing.response_timeout_ms)),
      speed_mm_s_(profile_.default_speed_mm_s) {
  const RegisterMap& r = profile_.registers;
  const int w = profile_.position_registers();
  // A single-axis drive has no second read-back: its actual_x stands in.
  const int actual_y = profile_.single_axis() ? r.actual_x : r.actual_y;
  // Without a second status register, status stands in for it.
  const int moving = r.moving_status >= 0 ? r.moving_status : r.status;
  const int first = std::min({r.actual_x, actual_y, r.status, r.alarm, moving});
  const int last = std::max({r.actual_x + w - 1, actual_y + w - 1, r.status, r.alarm, moving});
  if (last - first + 1 <= kMaxReadRegisters) {
    feedback_first_ = first;
    feedback_count_ = last - first + 1;
  }
  reconnect("connect", /*first=*/true);
}

std::string ModbusBench::where() const {
  std::string w = "bench " + link_.url().str();
  if (profile_.single_axis())
    w += std::string(" (") + (profile_.axis == 'x' ? "X" : "Y") + " axis drive)";
  return w;
}

std::string ModbusBench::at(const XY& p) const {
  if (profile_.single_axis()) return config::format_number(p.x_mm) + " mm";
  return "(" + config::format_number(p.x_mm) + ", " + config::format_number(p.y_mm) + ") mm";
}

void ModbusBench::reconnect(const char* what, bool first) {
  const auto deadline = Clock::now() + milliseconds(profile_.timing.reconnect_timeout_ms);
  milliseconds backoff = kBackoffFirst;
  int err = 0;
  for (;;) {
    err = link_.connect();
    BenchStatus s;
    if (err == 0) err = read_feedback(s);
    if (err == 0) {
      // The first connection only learns the state (an alarm is for the
      // caller to see and reset); a reconnect checks it against what was
      // commanded.
      if (first) {
        homed_seen_ = s.homed;
        return;
      }
      err = check_state_after_reconnect(s);
      if (err == 0) return;
    }
    if (!ModbusLink::is_link_error(err)) {
      throw BenchError(where() + ": reading the bench state after " + what +
                       " failed: " + ModbusLink::describe(err) +
                       " (do the profile's registers exist on this drive?)");
    }
    link_.close();
    if (Clock::now() + backoff > deadline) break;
    std::this_thread::sleep_for(backoff);
    backoff = std::min(backoff * 2, kBackoffMax);
  }
  throw BenchLinkError(link_down_message(what, first, err));
}

std::string ModbusBench::link_down_message(const char* what, bool first, int err) const {
  const std::string window =
      "link.reconnect_timeout_ms = " + std::to_string(profile_.timing.reconnect_timeout_ms) + " ms";
  std::string msg = where() + ": ";
  msg += first ? "cannot connect (tried for " + window + ")"
               : std::string("link down during ") + what + ", not re-established within " + window;
  msg += ": " + ModbusLink::describe(err) + ": " + link_hint(err);
  return msg;
}

std::string ModbusBench::link_hint(int err) const {
  const BenchUrl& url = link_.url();
  const bool tcp = url.transport == BenchUrl::Transport::kTcp;
  const std::string unit = std::to_string(url.unit.value_or(profile_.unit_id));
  const std::string timeout =
      "link.response_timeout_ms = " + std::to_string(profile_.timing.response_timeout_ms) + " ms";
  if (tcp && err == ECONNREFUSED) {
    return "nothing listens at " + url.host + ":" + std::to_string(url.port) +
           ". Is the bench (or its Modbus gateway) switched on and at that address, or, for the "
           "simulated rig, is `rig sim` (or `rig sim bench`) running?";
  }
  if (tcp && (err == EHOSTUNREACH || err == ENETUNREACH)) {
    return "no route to " + url.host + ": check the address and the network cable";
  }
  if (!tcp && (err == ENOENT || err == ENODEV || err == ENXIO)) {
    return "no serial device " + url.device + ": is the adapter plugged in (ls /dev/serial/by-id)?";
  }
  if (!tcp && err == EACCES) {
    return "this user may not open " + url.device +
           " (add it to the group that owns the device, "
           "usually dialout)";
  }
  if (err == ETIMEDOUT) {
    return tcp ? "no answer from unit " + unit + " within " + timeout +
                     ": is the address that of the bench, and its unit id that of link.unit_id "
                     "(or the URL's ?unit=)?"
               : "no answer from unit " + unit + " on " + url.device + " at " +
                     std::to_string(url.baud) + " baud, parity " + url.parity + ", " +
                     std::to_string(url.data_bits) + " data and " + std::to_string(url.stop_bits) +
                     " stop bits within " + timeout +
                     ": check the drive's unit id (link.unit_id or ?unit=), that baud, parity and "
                     "stop bits match the drive's serial settings, and the wiring (A/B swapped?)";
  }
  if (err == EMBBADSLAVE && !tcp) {
    const std::optional<int> other = link_.foreign_unit();
    return "the answer came from " +
           (other ? "unit " + std::to_string(*other) : std::string("another unit")) +
           ", not from unit " + unit +
           " that was asked, and is refused: is link.unit_id (or the URL's ?unit=) the drive's "
           "station address, and does no other device on the line answer for it?";
  }
  if (err == EMBBADCRC || err == EMBBADDATA || err == EMBBADSLAVE) {
    return tcp ? "the answers are not the drive's Modbus: is this port a Modbus TCP server?"
               : "garbled answers: baud, parity or stop bits of the URL differ from the drive's, "
                 "or two devices share unit " +
                     unit;
  }
  return "check that the bench is switched on and connected";
}

int ModbusBench::check_state_after_reconnect(const BenchStatus& s) {
  if (s.alarm) {
    throw BenchFault(where() + ": alarm " + std::to_string(s.alarm_code) + " (" + s.alarm_meaning +
                         ") found after reconnect",
                     s.alarm_code, s.alarm_meaning);
  }
  if (homed_seen_ && !s.homed) {
    pending_ = Pending::kNone;
    throw BenchLinkError(where() +
                         ": after reconnect the bench is no longer homed (drive restarted?); "
                         "its position is unknown: home it before moving");
  }
  if (s.homed) homed_seen_ = true;
  if (pending_ == Pending::kHome && !s.homed && !s.moving) {
    pending_ = Pending::kNone;
    throw BenchLinkError(where() +
                         ": after reconnect the bench is neither homing nor homed (drive "
                         "restarted?): home it again");
  }
  if (pending_ == Pending::kMove) {
    std::array<std::int32_t, 2> counts{};
    if (const int err = read_targets(counts); err != 0) return err;
    if (counts != target_counts_) {
      pending_ = Pending::kNone;
      throw BenchLinkError(where() + ": after reconnect the target registers hold (" +
                           std::to_string(counts[0]) + ", " + std::to_string(counts[1]) +
                           ") counts, not the commanded (" + std::to_string(target_counts_[0]) +
                           ", " + std::to_string(target_counts_[1]) + "): drive restarted?");
    }
  }
  spdlog::debug("bench {}: state read: ({}, {}) mm, homed {}, moving {}", link_.url().str(),
                s.position.x_mm, s.position.y_mm, s.homed, s.moving);
  return 0;
}

template <class Op>
int ModbusBench::transact(const char* what, Op op) {
  for (int attempt = 1;; ++attempt) {
    if (!link_.connected()) {
      reconnect(what, /*first=*/false);
      ++reconnects_;
      spdlog::warn("{}: link re-established during {}; state re-read, resuming", where(), what);
    }
    const int err = op();
    if (err == 0 || !ModbusLink::is_link_error(err)) return err;
    spdlog::warn("{}: link failed during {}: {} (attempt {} of {})", where(), what,
                 ModbusLink::describe(err), attempt, kMaxAttempts);
    link_.close();
    if (attempt == kMaxAttempts) {
      throw BenchLinkError(where() + ": " + what + " failed " + std::to_string(kMaxAttempts) +
                           " times in a row: " + ModbusLink::describe(err));
    }
  }
}

BenchStatus ModbusBench::decode_feedback(const std::uint16_t* block, int first) const {
  const RegisterMap& r = profile_.registers;
  const StatusBits& b = profile_.status_bits;
  BenchStatus s;
  s.position.x_mm = profile_.to_mm(profile_.decode_position(block + (r.actual_x - first)));
  if (!profile_.single_axis()) {
    s.position.y_mm = profile_.to_mm(profile_.decode_position(block + (r.actual_y - first)));
  }
  const std::uint16_t bits = block[r.status - first];
  s.status_word = bits;
  auto bit = [bits](int n) { return ((bits >> n) & 1u) != 0; };
  s.homed = bit(b.homed);
  s.moving = r.moving_status >= 0 ? ((block[r.moving_status - first] >> b.moving) & 1u) != 0
                                  : bit(b.moving);
  s.in_position = bit(b.in_position);
  s.alarm = bit(b.alarm);
  s.emergency_stop = bit(b.emergency_stop);
  s.alarm_code = block[r.alarm - first];
  if (s.alarm_code != 0) s.alarm_meaning = profile_.alarm_meaning(s.alarm_code);
  return s;
}

int ModbusBench::read_feedback(BenchStatus& out) {
  const RegisterMap& r = profile_.registers;
  if (feedback_count_ > 0) {
    std::uint16_t block[kMaxReadRegisters];
    const int err = link_.read(r.feedback, feedback_first_, feedback_count_, block);
    if (err == 0) out = decode_feedback(block, feedback_first_);
    return err;
  }
  // Scattered map: one read per field, assembled into a block indexed from 0.
  std::vector<std::uint16_t> block(65537, 0);
  const int w = profile_.position_registers();
  const int actual_y = profile_.single_axis() ? r.actual_x : r.actual_y;
  for (auto [addr, n] : {std::pair<int, int>{r.actual_x, w},
                         {actual_y, w},
                         {r.status, 1},
                         {r.alarm, 1},
                         {r.moving_status >= 0 ? r.moving_status : r.status, 1}}) {
    if (const int err = link_.read(r.feedback, addr, n, block.data() + addr); err != 0) return err;
  }
  out = decode_feedback(block.data(), 0);
  return 0;
}

int ModbusBench::read_targets(std::array<std::int32_t, 2>& counts) {
  const RegisterMap& r = profile_.registers;
  const int w = profile_.position_registers();
  std::uint16_t x[2], y[2] = {0, 0};
  if (int err = link_.read(RegisterTable::kHolding, r.target_x, w, x); err != 0) return err;
  if (!profile_.single_axis()) {
    if (int err = link_.read(RegisterTable::kHolding, r.target_y, w, y); err != 0) return err;
  }
  counts = {profile_.decode_position(x), profile_.single_axis() ? 0 : profile_.decode_position(y)};
  return 0;
}

void ModbusBench::write_verified(const char* what, const std::map<int, std::uint16_t>& values) {
  // Contiguous runs of addresses become one write (function 16) each.
  std::vector<std::pair<int, std::vector<std::uint16_t>>> runs;
  for (const auto& [addr, value] : values) {
    if (!runs.empty() && runs.back().first + static_cast<int>(runs.back().second.size()) == addr) {
      runs.back().second.push_back(value);
    } else {
      runs.push_back({addr, {value}});
    }
  }
  for (const auto& run : runs) {
    // Named, not structured bindings: C++17 lambdas cannot capture those
    // (clang refuses; the fuzz build uses clang).
    const auto addr = run.first;
    const auto& regs = run.second;
    const int n = static_cast<int>(regs.size());
    std::vector<std::uint16_t> back(regs.size());
    const int err = transact(what, [&] {
      if (int e = link_.write(addr, n, regs.data()); e != 0) return e;
      return link_.read(RegisterTable::kHolding, addr, n, back.data());
    });
    const std::string range =
        "holding registers " + std::to_string(addr) + ".." + std::to_string(addr + n - 1);
    if (err != 0) {
      throw BenchWriteError(where() + ": " + what + ": the drive refused " + range + ": " +
                            ModbusLink::describe(err));
    }
    if (back != regs) {
      std::ostringstream msg;
      msg << where() << ": " << what << ": " << range << " read back [";
      for (int i = 0; i < n; ++i)
        msg << (i ? " " : "") << back[i];
      msg << "] after writing [";
      for (int i = 0; i < n; ++i)
        msg << (i ? " " : "") << regs[i];
      msg << "]";
      throw BenchWriteError(msg.str());
    }
  }
}

std::uint16_t ModbusBench::held_bits() const {
  return servo_enabled_ ? profile_.protocol.servo_on : 0;
}

void ModbusBench::ensure_servo_on(const char* what) {
  const CommandProtocol& h = profile_.protocol;
  if (h.servo_on == 0) return;
  // Read every time: a drive that restarted, or tripped, drops the servo.
  if ((status().status_word >> h.servo_ready_bit) & 1u) {
    servo_enabled_ = true;
    return;
  }
  servo_enabled_ = true;
  write_verified(what, {{profile_.registers.command, h.servo_on}});
  const auto deadline = Clock::now() + milliseconds(h.accept_timeout_ms);
  for (;;) {
    const BenchStatus s = status();
    if ((s.status_word >> h.servo_ready_bit) & 1u) return;
    if (s.alarm || Clock::now() >= deadline) {
      servo_enabled_ = false;
      throw BenchWriteError(
          where() + ": " + what + ": servo not on (status bit " +
          std::to_string(h.servo_ready_bit) + " = handshake.servo_ready_bit still 0) " +
          (s.alarm ? "and alarm " + std::to_string(s.alarm_code) + " (" + s.alarm_meaning + ")"
                   : "within handshake.accept_timeout_ms = " + std::to_string(h.accept_timeout_ms) +
                         " ms") +
          " after writing handshake.servo_on = " + std::to_string(h.servo_on) +
          " to the command register: is the drive's main power on and its emergency stop "
          "released?");
    }
    std::this_thread::sleep_for(milliseconds(profile_.timing.poll_interval_ms));
  }
}

void ModbusBench::write_unverified(const char* what, int address, std::uint16_t value) {
  const int err = transact(what, [&] { return link_.write(address, 1, &value); });
  if (err != 0) {
    throw BenchWriteError(where() + ": " + what + ": the drive refused " + "holding register " +
                          std::to_string(address) + ": " + ModbusLink::describe(err));
  }
}

bool ModbusBench::accepted(Acceptance kind, const BenchStatus& before, const BenchStatus& s,
                           const std::optional<XY>& target) const {
  if (s.alarm || s.emergency_stop) return true;  // the drive's answer; wait_settled reports it
  const double tol = profile_.position_tolerance_mm + 1e-6;
  const bool at_target = target && std::fabs(s.position.x_mm - target->x_mm) <= tol &&
                         std::fabs(s.position.y_mm - target->y_mm) <= tol;
  switch (kind) {
    case Acceptance::kMotion:
      // Moving, or in position lost, or already there (a move shorter than
      // one poll interval, or to where the bench stands).
      return s.moving || (before.in_position && !s.in_position) ||
             (at_target && s.in_position && !s.moving);
    case Acceptance::kHoming:
      return s.moving || (before.homed && !s.homed) || (at_target && s.homed && !s.moving);
    case Acceptance::kStill:
      return !s.moving;
    case Acceptance::kAlarmCleared:
      return !s.alarm;
  }
  return false;
}

void ModbusBench::command(const char* what, std::uint16_t code, Acceptance kind,
                          const std::optional<XY>& target) {
  const CommandProtocol& h = profile_.protocol;
  const int reg = profile_.registers.command;
  const auto word = static_cast<std::uint16_t>(code | held_bits());
  if (h.handshake == CommandHandshake::kKept) {
    write_verified(what, {{reg, word}});
    return;
  }
  const BenchStatus before = status();
  const auto deadline = Clock::now() + milliseconds(h.accept_timeout_ms);
  if (h.handshake == CommandHandshake::kSelfClearing) {
    write_unverified(what, reg, word);
    for (;;) {
      const BenchStatus s = status();
      if (accepted(kind, before, s, target)) return;
      if (Clock::now() >= deadline) {
        throw BenchWriteError(
            where() + ": " + what + ": the drive did not take command " + std::to_string(word) +
            " within handshake.accept_timeout_ms = " + std::to_string(h.accept_timeout_ms) +
            " ms (the status shows no sign of it: moving " + std::to_string(s.moving) +
            ", in position " + std::to_string(s.in_position) + ", homed " +
            std::to_string(s.homed) + ")");
      }
      std::this_thread::sleep_for(milliseconds(profile_.timing.poll_interval_ms));
    }
  }
  // Edge-triggered: set, wait for the acknowledge (or hold pulse_ms), clear.
  write_verified(what, {{reg, word}});
  if (h.ack_bit < 0) {
    std::this_thread::sleep_for(milliseconds(h.pulse_ms));
  } else {
    for (;;) {
      const BenchStatus s = status();
      if (((s.status_word >> h.ack_bit) & 1u) || s.alarm) break;
      if (Clock::now() >= deadline) {
        write_verified(what, {{reg, held_bits()}});
        throw BenchWriteError(where() + ": " + what + ": the drive did not acknowledge command " +
                              std::to_string(word) + " (status bit " + std::to_string(h.ack_bit) +
                              " = handshake.ack_bit) within handshake.accept_timeout_ms = " +
                              std::to_string(h.accept_timeout_ms) + " ms");
      }
      std::this_thread::sleep_for(milliseconds(profile_.timing.poll_interval_ms));
    }
  }
  write_verified(what, {{reg, held_bits()}});
}

void ModbusBench::check_speed(double speed_mm_s) const {
  // One drive of several is named; a controller's message is the bench's own.
  const std::string who = profile_.single_axis() ? where() + ": " : "";
  if (!(speed_mm_s > 0) || speed_mm_s > profile_.max_speed_mm_s) {
    throw SoftLimitError(who + "speed " + config::format_number(speed_mm_s) +
                         " mm/s is outside (0, " + config::format_number(profile_.max_speed_mm_s) +
                         "] (motion.max_speed_mm_s of " + profile_.source + ")");
  }
  // The drive takes the speed as an integer in its own units; one that
  // rounds to 0 is refused by the drive (or means "stand still").
  if (std::lround(speed_mm_s * profile_.speed_units_per_mm_s) < 1) {
    throw SoftLimitError(who + "speed " + config::format_number(speed_mm_s) +
                         " mm/s rounds to 0 in the drive's units (" +
                         config::format_number(profile_.speed_units_per_mm_s) + " per mm/s, " +
                         profile_.source + "); expected at least " +
                         config::format_number(0.5 / profile_.speed_units_per_mm_s) + " mm/s");
  }
}

void ModbusBench::set_speed(double speed_mm_s) {
  check_speed(speed_mm_s);
  speed_mm_s_ = speed_mm_s;
}

void ModbusBench::move_to(double x_mm, double y_mm) {
  write_target(x_mm, y_mm);
  start_move();
}

std::array<std::int32_t, 2> ModbusBench::target_counts(double x_mm, double y_mm) const {
  const SoftLimits& lim = profile_.soft_limits;
  // A single-axis drive moves its own axis, given as x_mm; y_mm is not used.
  if (profile_.single_axis()) y_mm = 0;
  const bool inside = profile_.single_axis() ? x_mm >= lim.x_min_mm && x_mm <= lim.x_max_mm
                                             : lim.contains(x_mm, y_mm);
  if (!std::isfinite(x_mm) || !std::isfinite(y_mm) || !inside) {
    throw SoftLimitError(lim.refusal(x_mm, y_mm, profile_.source));
  }
  // Quantize towards the inside: a target within half a count of a limit must
  // not round to a position beyond it.
  auto quantize = [&](double v, double lo, double hi) {
    std::int32_t c = profile_.to_counts(v);
    if (profile_.to_mm(c) > hi)
      c = static_cast<std::int32_t>(std::floor(hi * profile_.counts_per_mm));
    if (profile_.to_mm(c) < lo)
      c = static_cast<std::int32_t>(std::ceil(lo * profile_.counts_per_mm));
    return c;
  };
  return {quantize(x_mm, lim.x_min_mm, lim.x_max_mm),
          profile_.single_axis() ? 0 : quantize(y_mm, lim.y_min_mm, lim.y_max_mm)};
}

void ModbusBench::write_target(double x_mm, double y_mm) {
  const std::array<std::int32_t, 2> counts = target_counts(x_mm, y_mm);
  const RegisterMap& r = profile_.registers;
  std::map<int, std::uint16_t> regs;
  const int w = profile_.position_registers();
  std::uint16_t words[2];
  std::vector<std::pair<int, std::int32_t>> targets = {{r.target_x, counts[0]}};
  if (!profile_.single_axis()) targets.push_back({r.target_y, counts[1]});
  for (auto [addr, c] : targets) {
    profile_.encode_position(c, words);
    for (int i = 0; i < w; ++i)
      regs[addr + i] = words[i];
  }
  regs[r.speed] =
      static_cast<std::uint16_t>(std::lround(speed_mm_s_ * profile_.speed_units_per_mm_s));

  // The previous target no longer describes the drive while this one is being
  // written: a reconnect in between re-reads and resumes the write.
  pending_ = Pending::kNone;
  written_.reset();
  ensure_servo_on("move_to");
  write_verified("move_to (targets)", regs);
  written_ = counts;
}

void ModbusBench::start_move() {
  if (!written_) {
    throw BenchError(where() + ": start_move without a target written (write_target first)");
  }
  const std::array<std::int32_t, 2> counts = *written_;
  const XY target{profile_.to_mm(counts[0]), profile_.to_mm(counts[1])};
  command("move_to (command)", profile_.commands.move_absolute, Acceptance::kMotion, target);
  written_.reset();
  pending_ = Pending::kMove;
  target_counts_ = counts;
  target_mm_ = target;
}

XY ModbusBench::target_registers() {
  std::array<std::int32_t, 2> counts{};
  const int err = transact("reading the targets", [&] { return read_targets(counts); });
  if (err != 0) {
    throw BenchError(where() +
                     ": reading the target registers failed: " + ModbusLink::describe(err) +
                     " (check registers.target* of " + profile_.source + ")");
  }
  return {profile_.to_mm(counts[0]), profile_.to_mm(counts[1])};
}

void ModbusBench::home() {
  pending_ = Pending::kNone;
  ensure_servo_on("home");
  command("home", profile_.commands.home, Acceptance::kHoming,
          XY{profile_.home_x_mm, profile_.home_y_mm});
  // The drive loses its reference while it homes; from here homed is
  // re-learnt from the drive.
  homed_seen_ = false;
  pending_ = Pending::kHome;
  target_mm_ = XY{profile_.home_x_mm, profile_.home_y_mm};
}

void ModbusBench::stop() {
  command("stop", profile_.commands.stop, Acceptance::kStill, std::nullopt);
  pending_ = Pending::kStop;
  target_mm_.reset();
}

void ModbusBench::reset_alarm() {
  const CommandProtocol& h = profile_.protocol;
  if (h.reset_pulse) {
    // A reset on the rising edge: set, hold, clear (keeping the servo on).
    write_verified("reset_alarm (pulse set)",
                   {{profile_.registers.command,
                     static_cast<std::uint16_t>(profile_.commands.reset_alarm | held_bits())}});
    std::this_thread::sleep_for(milliseconds(h.pulse_ms));
    write_verified("reset_alarm (pulse clear)", {{profile_.registers.command, held_bits()}});
  } else {
    command("reset_alarm", profile_.commands.reset_alarm, Acceptance::kAlarmCleared, std::nullopt);
  }
  const BenchStatus s = status();
  if (s.alarm) {
    throw BenchFault(where() + ": alarm " + std::to_string(s.alarm_code) + " (" + s.alarm_meaning +
                         ") persists after reset",
                     s.alarm_code, s.alarm_meaning);
  }
}

BenchStatus ModbusBench::status() {
  BenchStatus s;
  const int err = transact("status", [&] { return read_feedback(s); });
  if (err != 0) {
    throw BenchError(where() + ": reading the status failed: " + ModbusLink::describe(err) +
                     " (check registers.* of " + profile_.source + ")");
  }
  if (s.homed) homed_seen_ = true;
  return s;
}

XY ModbusBench::position() {
  return status().position;
}

BenchStatus ModbusBench::checked_status() {
  const BenchStatus s = status();
  if (s.alarm) {
    pending_ = Pending::kNone;
    throw BenchFault(where() + ": alarm " + std::to_string(s.alarm_code) + " (" + s.alarm_meaning +
                         ") at " + at(s.position),
                     s.alarm_code, s.alarm_meaning);
  }
  if (s.emergency_stop) {
    pending_ = Pending::kNone;
    throw BenchFault(where() + ": emergency stop at " + at(s.position), s.alarm_code,
                     s.alarm_code ? s.alarm_meaning : "emergency stop");
  }
  return s;
}

bool ModbusBench::on_target(const BenchStatus& s) const {
  // A read-back within the tolerance, plus a hair (1 nm) for the mm <-> counts
  // conversion in floating point.
  const double tol = profile_.position_tolerance_mm + 1e-6;
  bool ok = !s.moving;
  if (pending_ != Pending::kStop && pending_ != Pending::kNone) ok = ok && s.in_position;
  if (pending_ == Pending::kHome) ok = ok && s.homed;
  if (target_mm_) {
    ok = ok && std::fabs(s.position.x_mm - target_mm_->x_mm) <= tol &&
         std::fabs(s.position.y_mm - target_mm_->y_mm) <= tol;
  }
  return ok;
}

std::string ModbusBench::describe_state(const BenchStatus& s) const {
  std::ostringstream msg;
  msg << "at " << at(s.position);
  if (target_mm_) msg << ", target " << at(*target_mm_);
  msg << ", moving " << s.moving << ", in position " << s.in_position << ", homed " << s.homed;
  return msg.str();
}

BenchStatus ModbusBench::wait_settled(milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  SettleWatch watch(milliseconds(profile_.timing.settle_time_ms));
  for (;;) {
    const BenchStatus s = checked_status();
    const auto now = Clock::now();
    if (watch.settled(on_target(s), now)) return s;
    if (now >= deadline) {
      throw BenchTimeout(where() + ": not settled after " + std::to_string(timeout.count()) +
                         " ms: " + describe_state(s));
    }
    std::this_thread::sleep_for(milliseconds(profile_.timing.poll_interval_ms));
  }
}

}  // namespace motion
