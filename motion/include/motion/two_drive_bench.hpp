// motion::TwoDriveBench: an XY bench made of two single-axis drives, an X
// drive and a Y drive, each a ModbusBench on its own link (two unit ids on one
// port or serial line, or two addresses) with its own register map and
// command conventions (DriveProfile::axis_drives).
//
// What the bench does with two drives:
//  - move_to checks the bench's soft limits before anything is sent to either
//    drive, then writes both drives' targets, then starts X, then Y. A drive
//    that refuses its target leaves both standing; a Y drive that does not
//    start has X stopped. Either raises BenchWriteError with the drive's
//    answer and, for each drive, where it stands and what its target
//    registers hold. home() starts both homing;
//  - set_speed checks the speed against both drives before either takes it:
//    both keep the old speed when one refuses (SoftLimitError naming it);
//  - wait_settled polls both drives and returns once both are settled
//    together for the shared settle time; an alarm or emergency stop on one
//    drive stops the other and raises BenchFault naming the drive
//    ("bench URL (Y axis drive): alarm 4 (...) at 12.5 mm");
//  - stop() and reset_alarm() reach both drives even when the first fails,
//    then raise the first error;
//  - each drive keeps its own reconnect watchdog (ModbusBench): a link drop
//    on one axis is ridden out on that axis alone, and a link that stays down
//    raises BenchLinkError naming that drive and its URL;
//  - status() combines both: homed and in position when both are, moving or
//    in alarm when either is; the alarm code and meaning are the first drive
//    in alarm's, the meaning prefixed with its axis ("Y axis: ..."); the
//    status word holds X's register in bits 0..15 and Y's in bits 16..31.
//
// Not thread-safe: one bench, one thread.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "motion/driven_bench.hpp"
#include "motion/modbus_bench.hpp"

namespace motion {

class TwoDriveBench : public DrivenBench {
 public:
  // `profile` must have axis_drives (a [x]/[y] file). Connects the X drive,
  // then the Y drive (see open_bench for which URL each takes).
  TwoDriveBench(const BenchUrl& url, DriveProfile profile);

  void home() override;
  void move_to(double x_mm, double y_mm) override;
  BenchStatus wait_settled(std::chrono::milliseconds timeout) override;
  XY position() override;
  BenchStatus status() override;
  void stop() override;
  void reset_alarm() override;
  void set_speed(double speed_mm_s) override;
  const DriveProfile& profile() const override { return profile_; }
  int reconnects() const override { return x_->reconnects() + y_->reconnects(); }

  // Each drive, for logs and tests.
  ModbusBench& x_drive() { return *x_; }
  ModbusBench& y_drive() { return *y_; }

 private:
  // Stops `other` after `failed` raised, logging (not raising) what the stop
  // itself raises.
  static void stop_quietly(ModbusBench& other, const char* why);
  // "DRIVE stands at P mm, its target registers hold T mm (what)", read
  // from the drive, for the message of a move that reached one drive only.
  static std::string holdings(ModbusBench& d, const char* what);

  DriveProfile profile_;
  std::unique_ptr<ModbusBench> x_;
  std::unique_ptr<ModbusBench> y_;
};

}  // namespace motion
