// sim::bench::BenchDynamics: the mechanics of the simulated XY bench, without any
// networking. Per axis a trapezoidal velocity profile (accelerate at accel,
// cruise at the commanded speed, decelerate so as to stop on the target),
// integrated in sub-steps of at most 0.25 ms of simulated time; a backlash
// deadband between motor and carriage; a random repeatability error of the
// carriage at each stop; encoder scale error, thermal drift and residual
// vibration after a stop (AxisConfig); travel limits, homing, alarms,
// emergency stop.
//
// Two positions exist, as on a real rig: the encoder read-back (motor
// position, quantized), which is all the driver ever sees, and the actual
// carriage position (with backlash and repeatability error), which only the
// simulated camera sees.
//
// Not thread-safe: BenchServer calls it under its mutex.
#pragma once

#include <optional>
#include <random>

#include "sim/bench/config.hpp"

namespace sim::bench {

class BenchDynamics {
 public:
  // home_*_mm: where homing ends (the profile's home). Precondition: a valid
  // config (positive speeds, accelerations, time scale).
  BenchDynamics(const BenchSimConfig& config, double home_x_mm, double home_y_mm);

  // Advances simulated time by dt_s seconds.
  void advance(double dt_s);

  // Commands, as the drive receives them. A move is refused with an alarm
  // when not homed (require_homing), outside the travel, or at speed <= 0;
  // ignored during an alarm or an emergency stop.
  void move(double x_mm, double y_mm, double speed_mm_s);
  void home();
  void stop();                       // decelerate to a standstill
  void reset_alarm();                // clears the alarm (not an emergency stop)
  void raise_alarm(int code);        // decelerates to a standstill, alarm bit + code
  void set_emergency_stop(bool on);  // on: immediate standstill, moves ignored
  // The drive loses power and comes back: both axes stand where they are
  // (absolute encoders), the homing is lost (when require_homing), any
  // homing or alarm is cleared.
  void power_cycle();
  void arm_alarm_at(const std::optional<AlarmAt>& at) { alarm_at_ = at; }

  double encoder_x_mm() const { return quantize(x_.motor); }
  double encoder_y_mm() const { return quantize(y_.motor); }
  // The carriage's true position: the motor's through the backlash, the
  // repeatability error of the last stop, the encoder scale error, the
  // thermal drift and the residual vibration (AxisConfig).
  double actual_x_mm() const { return actual(x_); }
  double actual_y_mm() const { return actual(y_); }
  // Simulated seconds since construction.
  double time_s() const { return time_s_; }
  bool homed() const { return homed_; }
  bool homing() const { return homing_; }
  bool moving() const { return x_.moving || y_.moving; }
  bool in_position() const;
  bool alarm() const { return alarm_code_ != kAlarmNone; }
  int alarm_code() const { return alarm_code_; }
  bool emergency_stop() const { return estop_; }
  // Target of the last accepted move (or the home after homing), mm.
  double commanded_x_mm() const { return commanded_x_; }
  double commanded_y_mm() const { return commanded_y_; }
  // True once after homing completes (the server then sets the target
  // registers to the home position, so that in-position is meaningful).
  bool take_homing_completed();

 private:
  struct Axis {
    AxisConfig cfg;
    double motor = 0;     // mm, what the encoder measures
    double v = 0;         // mm/s
    double target = 0;    // mm, where the current profile ends
    double vmax = 0;      // mm/s, cruise speed of the current profile
    double carriage = 0;  // mm, follows motor within the backlash deadband
    double error = 0;     // mm, repeatability error drawn at the last stop
    bool moving = false;
    double stop_time_s = -1e9;  // when the axis last stopped (vibration)
    double stop_dir = 0;        // sign of the last move (vibration direction)
  };
  double actual(const Axis& a) const;

  void step(Axis& a, double h);
  void start(Axis& a, double target, double speed);
  void decelerate(Axis& a);
  double quantize(double mm) const;

  BenchSimConfig config_;
  double home_x_, home_y_;
  Axis x_, y_;
  bool homed_;
  bool homing_ = false;
  bool homing_completed_ = false;
  int alarm_code_ = kAlarmNone;
  bool estop_ = false;
  double commanded_x_, commanded_y_;
  std::optional<AlarmAt> alarm_at_;
  double time_s_ = 0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace sim::bench
