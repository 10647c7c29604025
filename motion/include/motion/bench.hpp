// motion::Bench: the XY robot bench as the controller sees it. The controller
// never knows which bench it talks to (ModbusBench over TCP or RTU, a real
// drive or the simulated one); it only ever sees read-back positions.
//
// Units: mm for positions, mm/s for speeds. Axes as printed on the bench.
#pragma once

#include <chrono>
#include <string>

namespace motion {

struct XY {
  double x_mm = 0;
  double y_mm = 0;
};

// One read of the drive's feedback: read-back position and status bits.
struct BenchStatus {
  XY position;  // read-back (encoder), mm
  bool homed = false;
  bool moving = false;
  bool in_position = false;
  bool alarm = false;
  bool emergency_stop = false;
  int alarm_code = 0;         // 0 = none
  std::string alarm_meaning;  // from the profile's [alarms] table; empty when code is 0
  unsigned status_word = 0;   // the status register as read, for drive-specific bits
};

class Bench {
 public:
  virtual ~Bench() = default;

  // Starts homing; wait_settled() returns once the bench is homed and still.
  virtual void home() = 0;
  // Starts an absolute move. Throws SoftLimitError, having sent nothing, if
  // (x_mm, y_mm) is outside the soft limits or not finite.
  virtual void move_to(double x_mm, double y_mm) = 0;
  // Blocks until the bench is settled: not moving, in position, the read-back
  // within the profile's tolerance of the last target (and homed after
  // home()), continuously for the profile's settle time. Returns the status
  // read last. Throws BenchFault on an alarm or emergency stop, BenchTimeout
  // when `timeout` elapses first.
  virtual BenchStatus wait_settled(std::chrono::milliseconds timeout) = 0;
  // The read-back position, mm.
  virtual XY position() = 0;
  virtual BenchStatus status() = 0;
  // Decelerates to a stop; wait_settled() then waits for standstill only.
  virtual void stop() = 0;
  // Clears a drive alarm. Throws BenchFault if the alarm persists.
  virtual void reset_alarm() = 0;
};

}  // namespace motion
