// Mechanics of the simulated bench (see sim/bench/dynamics.hpp).
#include "sim/bench/dynamics.hpp"

#include <algorithm>
#include <cmath>

namespace sim::bench {
namespace {

// Largest integration step, s of simulated time. At 100 mm/s a step moves
// 25 µm, fine enough for alarm_at radii of 0.1 mm and more.
constexpr double kMaxStepS = 0.25e-3;

}  // namespace

BenchDynamics::BenchDynamics(const BenchSimConfig& config, double home_x_mm, double home_y_mm)
    : config_(config),
      home_x_(home_x_mm),
      home_y_(home_y_mm),
      homed_(!config.require_homing),
      rng_(config.seed) {
  for (auto [axis, cfg] : {std::pair<Axis*, const AxisConfig*>{&x_, &config.x}, {&y_, &config.y}}) {
    axis->cfg = *cfg;
    axis->motor = axis->carriage = axis->target = cfg->initial_mm;
  }
  commanded_x_ = x_.motor;
  commanded_y_ = y_.motor;
  alarm_at_ = config.faults.alarm_at;
}

double BenchDynamics::quantize(double mm) const {
  const double r = config_.encoder_resolution_mm;
  return std::round(mm / r) * r;
}

double BenchDynamics::actual(const Axis& a) const {
  const AxisConfig& c = a.cfg;
  double mm = (a.carriage + a.error) / (1 + c.encoder_scale_ppm * 1e-6);
  mm += c.thermal_drift_um_per_min * 1e-3 * time_s_ / 60;
  if (c.vibration_amplitude_mm > 0 && !a.moving) {
    const double t = time_s_ - a.stop_time_s;
    mm += a.stop_dir * c.vibration_amplitude_mm * std::exp(-t / c.vibration_decay_s) *
          std::cos(2 * M_PI * c.vibration_frequency_hz * t);
  }
  return mm;
}

bool BenchDynamics::in_position() const {
  const double band = config_.in_position_band_mm + 1e-9;
  return !moving() && !homing_ && std::fabs(encoder_x_mm() - commanded_x_) <= band &&
         std::fabs(encoder_y_mm() - commanded_y_) <= band;
}

bool BenchDynamics::take_homing_completed() {
  const bool done = homing_completed_;
  homing_completed_ = false;
  return done;
}

void BenchDynamics::start(Axis& a, double target, double speed) {
  a.target = target;
  a.vmax = std::min(speed, a.cfg.max_speed_mm_s);
  a.moving = a.target != a.motor || a.v != 0;
}

void BenchDynamics::decelerate(Axis& a) {
  // Stopping distance at constant deceleration: v^2 / (2 a).
  a.target = a.motor + a.v * std::fabs(a.v) / (2 * a.cfg.accel_mm_s2);
  a.vmax = std::max(std::fabs(a.v), 1e-9);
}

void BenchDynamics::step(Axis& a, double h) {
  if (!a.moving) return;
  const double acc = a.cfg.accel_mm_s2;
  const double d = a.target - a.motor;
  const double dir = d >= 0 ? 1.0 : -1.0;
  const double dist = std::fabs(d);
  const double v_toward = a.v * dir;  // speed towards the target (< 0: moving away)
  // Speed from which the axis stops exactly on the target at full
  // deceleration: the braking branch of the trapezoid, v = sqrt(2 a d).
  const double v_brake = std::sqrt(2 * acc * dist);
  if (v_toward > 0 && v_toward >= v_brake - acc * h) {
    // Braking: follow the parabola exactly. With d' = -sqrt(2 a d),
    // sqrt(d) falls linearly at sqrt(a/2) per second.
    const double root = std::sqrt(dist) - std::sqrt(acc / 2) * h;
    if (root <= 0) {
      a.motor = a.target;
      a.v = 0;
      a.moving = false;
      a.stop_time_s = time_s_ + h;
      a.stop_dir = dir;
      a.error = a.cfg.repeatability_mm * normal_(rng_);
    } else {
      a.motor = a.target - dir * root * root;
      a.v = dir * std::sqrt(2 * acc) * root;
    }
  } else {
    // Accelerating towards the cruise speed (or turning round): constant
    // acceleration over the step, integrated exactly.
    const double desired = dir * std::min(a.vmax, v_brake);
    const double v0 = a.v;
    a.v += std::clamp(desired - a.v, -acc * h, acc * h);
    a.motor += (v0 + a.v) / 2 * h;
  }
  const double half = a.cfg.backlash_mm / 2;
  if (a.motor - a.carriage > half) a.carriage = a.motor - half;
  if (a.motor - a.carriage < -half) a.carriage = a.motor + half;
}

void BenchDynamics::advance(double dt_s) {
  while (dt_s > 0) {
    const double h = std::min(dt_s, kMaxStepS);
    dt_s -= h;
    const bool was_moving = moving();
    step(x_, h);
    step(y_, h);
    time_s_ += h;
    if (alarm_at_ && was_moving &&
        std::hypot(x_.motor - alarm_at_->x_mm, y_.motor - alarm_at_->y_mm) <=
            alarm_at_->radius_mm) {
      const int code = alarm_at_->code;
      alarm_at_.reset();
      raise_alarm(code);
    }
    if (homing_ && !moving()) {
      homing_ = false;
      homed_ = true;
      homing_completed_ = true;
      commanded_x_ = home_x_;
      commanded_y_ = home_y_;
    }
  }
}

void BenchDynamics::move(double x_mm, double y_mm, double speed_mm_s) {
  if (alarm() || estop_) return;
  if (config_.require_homing && !homed_) return raise_alarm(kAlarmNotHomed);
  if (speed_mm_s <= 0) return raise_alarm(kAlarmBadCommand);
  if (x_mm < x_.cfg.travel_min_mm || x_mm > x_.cfg.travel_max_mm || y_mm < y_.cfg.travel_min_mm ||
      y_mm > y_.cfg.travel_max_mm) {
    return raise_alarm(kAlarmLimit);
  }
  homing_ = false;
  commanded_x_ = x_mm;
  commanded_y_ = y_mm;
  start(x_, x_mm, speed_mm_s);
  start(y_, y_mm, speed_mm_s);
}

void BenchDynamics::home() {
  if (alarm() || estop_) return;
  homed_ = false;
  homing_ = true;
  start(x_, home_x_, config_.homing_speed_mm_s);
  start(y_, home_y_, config_.homing_speed_mm_s);
  // Already there: homing completes on the next step.
}

void BenchDynamics::power_cycle() {
  for (Axis* a : {&x_, &y_}) {
    a->v = 0;
    a->target = a->motor;
    a->moving = false;
  }
  homed_ = !config_.require_homing;
  homing_ = false;
  alarm_code_ = kAlarmNone;
}

void BenchDynamics::stop() {
  homing_ = false;
  decelerate(x_);
  decelerate(y_);
}

void BenchDynamics::reset_alarm() {
  if (!estop_) alarm_code_ = kAlarmNone;
}

void BenchDynamics::raise_alarm(int code) {
  alarm_code_ = code;
  if (homing_) homing_ = false;
  decelerate(x_);
  decelerate(y_);
}

void BenchDynamics::set_emergency_stop(bool on) {
  estop_ = on;
  if (!on) return;
  homing_ = false;
  for (Axis* a : {&x_, &y_}) {
    a->v = 0;
    a->target = a->motor;
    a->moving = false;
  }
}

}  // namespace sim::bench
