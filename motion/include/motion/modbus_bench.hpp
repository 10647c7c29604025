// motion::ModbusBench: a Bench driven over Modbus (TCP or RTU) by a
// DriveProfile: one controller of both axes, or (profile.axis 'x' or 'y') one
// single-axis drive, whose axis it reports as x_mm (y_mm is 0) and moves with
// move_to(mm, any). Everything drive-specific (addresses, word order, units, bits,
// command codes, timeouts, alarm texts, soft limits) comes from the profile.
//
// Guarantees:
//  - a target outside the profile's soft limits is refused before anything is
//    sent (SoftLimitError); a target inside is quantized to counts towards the
//    inside, so no position outside the limits is ever written;
//  - every write is read back and compared (BenchWriteError on a mismatch or
//    a Modbus exception response), except a command to a drive that clears
//    its command register itself: its acceptance is read from the status
//    instead. Commands follow the profile's [handshake]: kept, self-clearing,
//    or an edge-triggered pulse (set, acknowledge, clear), with the servo-on
//    bits written before the first home or move and kept set;
//  - a link that stays down raises BenchLinkError naming the likely cause
//    (nothing listening, no route, no serial device, no answer from the
//    unit, garbled answers) and what to check;
//  - reconnect watchdog: when the link fails (timeout, reset, EPIPE, garbled
//    frame) the link is closed and re-opened with exponential backoff
//    (10 ms doubling to 500 ms) for up to the profile's reconnect_timeout_ms.
//    After every reconnect the bench state is re-read before anything else:
//    an alarm raises BenchFault; a bench that has lost its home, or whose
//    target registers no longer hold the target of a move in progress, raises
//    BenchLinkError (a drive that restarted); otherwise the interrupted
//    operation is repeated (all of them are idempotent: absolute targets and
//    reads) and the caller never notices.
//
// Not thread-safe: one bench, one thread.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "motion/bench.hpp"
#include "motion/bench_url.hpp"
#include "motion/drive_profile.hpp"
#include "motion/driven_bench.hpp"
#include "motion/modbus_link.hpp"

namespace motion {

class ModbusBench : public DrivenBench {
 public:
  // Connects (with the reconnect watchdog) and reads the status once. Throws
  // BenchLinkError if the drive cannot be reached within the profile's
  // reconnect timeout.
  ModbusBench(const BenchUrl& url, DriveProfile profile);

  void home() override;
  void move_to(double x_mm, double y_mm) override;
  BenchStatus wait_settled(std::chrono::milliseconds timeout) override;
  XY position() override;
  BenchStatus status() override;
  void stop() override;
  void reset_alarm() override;

  // Speed written with every following move, mm/s. Throws SoftLimitError if
  // not in (0, profile.max_speed_mm_s] (NaN included) or if it rounds to 0 in
  // the drive's units (profile.speed_units_per_mm_s).
  void set_speed(double speed_mm_s) override;
  // What set_speed checks, without setting anything: throws SoftLimitError
  // (naming this drive) for a speed set_speed refuses.
  void check_speed(double speed_mm_s) const;

  const DriveProfile& profile() const override { return profile_; }
  // How many times the watchdog has re-established the link (for logs, tests).
  int reconnects() const override { return reconnects_; }

  // The two steps of move_to, for a bench that moves several drives together
  // (TwoDriveBench). write_target: refuses a target outside the soft limits
  // (SoftLimitError, nothing sent), turns the servo on if the profile has
  // one, then writes and verifies the target and speed registers without
  // starting (BenchWriteError naming the registers and the drive's answer).
  // start_move: starts the move to the target last written (BenchError if
  // none was, BenchWriteError if the drive does not take the command).
  void write_target(double x_mm, double y_mm);
  void start_move();
  // The target registers as the drive holds them now, mm ((x, 0) for a
  // single-axis drive). Throws BenchError if they cannot be read.
  XY target_registers();

  // The steps of wait_settled, for a bench that waits on several drives
  // (TwoDriveBench). checked_status: the status, or BenchFault on an alarm or
  // emergency stop. on_target: whether `s` shows the drive where its last
  // command takes it (not moving, in position, at the target, homed after
  // home()), before the settle time. describe_state: `s` and the target, for
  // a timeout's message.
  BenchStatus checked_status();
  bool on_target(const BenchStatus& s) const;
  std::string describe_state(const BenchStatus& s) const;
  // "bench URL", with " (X axis drive)" for a single-axis drive: how every
  // message of this bench begins.
  std::string where() const;

 private:
  enum class Pending { kNone, kMove, kHome, kStop };

  // Runs `op` (returns 0 or an errno); on a link error reconnects and runs it
  // again, at most a few times. A Modbus exception response is returned.
  template <class Op>
  int transact(const char* what, Op op);
  // Connects with backoff until the profile's reconnect timeout, then reads
  // the state; unless `first`, checks it against what was commanded.
  void reconnect(const char* what, bool first);
  // Raises if the re-read state contradicts what was commanded; returns the
  // errno of a failed read (0 if none), after which the reconnect goes on.
  int check_state_after_reconnect(const BenchStatus& s);
  // The BenchLinkError text for a link that stayed down: what failed, the
  // last error, and what a person should check for it (link_hint).
  std::string link_down_message(const char* what, bool first, int err) const;
  std::string link_hint(int err) const;
  // A target in counts, checked against the soft limits and quantized
  // towards the inside; throws SoftLimitError.
  std::array<std::int32_t, 2> target_counts(double x_mm, double y_mm) const;
  int read_feedback(BenchStatus& out);
  int read_targets(std::array<std::int32_t, 2>& counts);
  // Writes registers (address -> value), grouped into contiguous runs, and
  // reads every run back.
  void write_verified(const char* what, const std::map<int, std::uint16_t>& values);
  // What shows that the drive took a command whose register it clears.
  enum class Acceptance { kMotion, kHoming, kStill, kAlarmCleared };
  // Writes a command code with the profile's handshake (kept: read back;
  // self-clearing: acceptance seen in the status; pulse: set, acknowledge,
  // clear), the servo-on bits held. `target`: where the command takes the
  // bench, for kMotion and kHoming. Throws BenchWriteError.
  void command(const char* what, std::uint16_t code, Acceptance kind,
               const std::optional<XY>& target);
  bool accepted(Acceptance kind, const BenchStatus& before, const BenchStatus& s,
                const std::optional<XY>& target) const;
  void write_unverified(const char* what, int address, std::uint16_t value);
  // The profile's servo-on, written and awaited when the status shows the servo off.
  void ensure_servo_on(const char* what);
  // The bits kept set in every command: the servo-on once it was written.
  std::uint16_t held_bits() const;
  BenchStatus decode_feedback(const std::uint16_t* block, int first) const;
  // A position as messages print it: "(x, y) mm", or "x mm" for one axis.
  std::string at(const XY& p) const;

  DriveProfile profile_;
  ModbusLink link_;
  double speed_mm_s_;
  // The contiguous feedback block read in one transaction, when it fits.
  int feedback_first_ = 0;
  int feedback_count_ = 0;

  // What the driver has commanded, to check against after a reconnect.
  Pending pending_ = Pending::kNone;
  std::optional<XY> target_mm_;
  std::array<std::int32_t, 2> target_counts_{};
  // The target written by write_target and not yet started.
  std::optional<std::array<std::int32_t, 2>> written_;
  bool homed_seen_ = false;
  bool servo_enabled_ = false;
  int reconnects_ = 0;
};

}  // namespace motion
