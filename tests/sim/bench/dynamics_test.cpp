// The mechanics of the simulated bench, without networking: trapezoidal
// move times, encoder quantization, backlash, repeatability error, travel
// limits and homing. Simulated time only, so these tests take no wall time.
#include "sim/bench/dynamics.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace {

// A bench already homed at (0, 0), no noise, no backlash, 1 µm encoder.
sim::bench::BenchSimConfig quiet_config() {
  sim::bench::BenchSimConfig c;
  c.require_homing = false;
  for (sim::bench::AxisConfig* a : {&c.x, &c.y}) {
    a->max_speed_mm_s = 100;
    a->accel_mm_s2 = 500;
    a->travel_min_mm = -5;
    a->travel_max_mm = 505;
    a->initial_mm = 0;
  }
  return c;
}

// Advances in 0.1 ms steps until the bench stops; returns the simulated time, s.
double run_until_still(sim::bench::BenchDynamics& d) {
  double t = 0;
  while (d.moving() && t < 100) {
    d.advance(1e-4);
    t += 1e-4;
  }
  return t;
}

TEST(BenchDynamics, OneMillimetreStepFollowsTheTriangularProfile) {
  sim::bench::BenchDynamics d(quiet_config(), 0, 0);
  d.move(1, 0, 50);
  // v^2/a = 5 mm > 1 mm: the profile never reaches 50 mm/s; it is a triangle
  // of duration 2 sqrt(d/a) = 2 sqrt(1/500) = 89.44 ms. The integrator runs
  // in 0.25 ms sub-steps and the loop in 0.1 ms steps: within 1 ms.
  EXPECT_NEAR(run_until_still(d), 2 * std::sqrt(1.0 / 500), 1e-3);
  EXPECT_DOUBLE_EQ(d.encoder_x_mm(), 1.0);
  EXPECT_TRUE(d.in_position());
}

TEST(BenchDynamics, LongMoveCruisesAtTheCommandedSpeed) {
  sim::bench::BenchDynamics d(quiet_config(), 0, 0);
  d.move(100, 0, 50);
  // Trapezoid: d/v + v/a = 100/50 + 50/500 = 2.1 s.
  EXPECT_NEAR(run_until_still(d), 2.1, 2e-3);
}

TEST(BenchDynamics, SpeedIsCappedAtTheAxisMaximum) {
  sim::bench::BenchDynamics d(quiet_config(), 0, 0);
  d.move(0, 100, 1000);
  // Capped at 100 mm/s: 100/100 + 100/500 = 1.2 s.
  EXPECT_NEAR(run_until_still(d), 1.2, 2e-3);
}

TEST(BenchDynamics, AxesRunTheirOwnProfiles) {
  sim::bench::BenchDynamics d(quiet_config(), 0, 0);
  d.move(1, 100, 50);
  d.advance(0.1);
  // X (89 ms triangle) has arrived while Y is still cruising.
  EXPECT_DOUBLE_EQ(d.encoder_x_mm(), 1.0);
  EXPECT_LT(d.encoder_y_mm(), 100);
  EXPECT_TRUE(d.moving());
}

TEST(BenchDynamics, EncoderQuantizesToItsResolution) {
  sim::bench::BenchSimConfig c = quiet_config();
  c.encoder_resolution_mm = 0.01;
  sim::bench::BenchDynamics d(c, 0, 0);
  d.move(1.234, 0, 50);
  run_until_still(d);
  EXPECT_NEAR(d.encoder_x_mm(), 1.23, 1e-12);
  EXPECT_NEAR(d.actual_x_mm(), 1.234, 1e-12);
}

TEST(BenchDynamics, BacklashLeavesTheCarriageBehindAfterAReversal) {
  sim::bench::BenchSimConfig c = quiet_config();
  c.x.backlash_mm = 0.05;
  sim::bench::BenchDynamics d(c, 0, 0);
  d.move(10, 0, 50);
  run_until_still(d);
  // Pushed in +x, the carriage trails the motor by half the deadband.
  EXPECT_NEAR(d.actual_x_mm() - d.encoder_x_mm(), -0.025, 1e-9);
  d.move(5, 0, 50);
  run_until_still(d);
  EXPECT_NEAR(d.actual_x_mm() - d.encoder_x_mm(), +0.025, 1e-9);
}

TEST(BenchDynamics, RepeatabilityErrorHasTheConfiguredSpread) {
  sim::bench::BenchSimConfig c = quiet_config();
  c.x.repeatability_mm = 0.01;
  sim::bench::BenchDynamics d(c, 0, 0);
  const int n = 2000;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    d.move(i % 2 ? 1 : 2, 0, 100);
    run_until_still(d);
    const double e = d.actual_x_mm() - d.encoder_x_mm();
    sum += e;
    sum2 += e * e;
  }
  const double mean = sum / n;
  const double sd = std::sqrt(sum2 / n - mean * mean);
  // Standard error of a normal sample's sd is sd / sqrt(2n) = 0.16 µm; of
  // the mean sd / sqrt(n) = 0.22 µm. Both checked at 5.5 standard errors. The
  // errors come from the config's seed, so every run draws the same ones
  // (measured: 1.8 and 1.1 standard errors off); another seed would fail
  // with probability 2 x 3.8e-8.
  EXPECT_NEAR(sd, 0.01, 0.00087);
  EXPECT_NEAR(mean, 0, 0.00123);
}

TEST(BenchDynamics, TargetOutsideTheTravelRaisesTheLimitAlarmAndDoesNotMove) {
  sim::bench::BenchDynamics d(quiet_config(), 0, 0);
  d.move(506, 0, 50);
  EXPECT_EQ(d.alarm_code(), sim::bench::kAlarmLimit);
  EXPECT_FALSE(d.moving());
}

TEST(BenchDynamics, MovesAreIgnoredDuringAnAlarmUntilReset) {
  sim::bench::BenchDynamics d(quiet_config(), 0, 0);
  d.raise_alarm(sim::bench::kAlarmFollowingError);
  d.move(1, 0, 50);
  EXPECT_FALSE(d.moving());
  d.reset_alarm();
  d.move(1, 0, 50);
  EXPECT_TRUE(d.moving());
}

TEST(BenchDynamics, HomingEndsAtHomeAndSetsHomed) {
  sim::bench::BenchSimConfig c = quiet_config();
  c.require_homing = true;
  c.x.initial_mm = 30;
  sim::bench::BenchDynamics d(c, 2, 3);
  EXPECT_FALSE(d.homed());
  d.move(1, 1, 50);
  EXPECT_EQ(d.alarm_code(), sim::bench::kAlarmNotHomed);
  d.reset_alarm();
  d.home();
  run_until_still(d);
  d.advance(1e-4);
  EXPECT_TRUE(d.homed());
  EXPECT_TRUE(d.take_homing_completed());
  EXPECT_DOUBLE_EQ(d.encoder_x_mm(), 2);
  EXPECT_DOUBLE_EQ(d.encoder_y_mm(), 3);
  EXPECT_TRUE(d.in_position());
}

TEST(BenchDynamics, StopDeceleratesAtTheConfiguredRate) {
  sim::bench::BenchDynamics d(quiet_config(), 0, 0);
  d.move(400, 0, 100);
  d.advance(1.0);  // cruising at 100 mm/s since 0.2 s
  const double at_stop = d.encoder_x_mm();
  d.stop();
  run_until_still(d);
  // Stopping distance v^2 / (2a) = 100^2 / 1000 = 10 mm.
  EXPECT_NEAR(d.encoder_x_mm() - at_stop, 10, 0.05);
  EXPECT_FALSE(d.in_position());
}

}  // namespace

namespace {

// Encoder scale error: the drive stops when the encoder reads the target, so
// the carriage is at target / (1 + ppm 1e-6): at 500 mm and +200 ppm, 100 um
// short (500 - 500 / 1.0002 = 99.98 um), while the read-back says 500.
TEST(BenchDynamics, EncoderScaleErrorLeavesTheCarriageShortOfTheReadBack) {
  sim::bench::BenchSimConfig c = quiet_config();
  c.x.encoder_scale_ppm = 200;
  sim::bench::BenchDynamics d(c, 0, 0);
  d.move(500, 0, 100);
  run_until_still(d);
  EXPECT_DOUBLE_EQ(d.encoder_x_mm(), 500.0);
  EXPECT_NEAR(d.actual_x_mm(), 500 / 1.0002, 1e-9);
  EXPECT_NEAR(d.actual_y_mm(), 0.0, 1e-12);
}

// Thermal drift: linear in simulated time, unseen by the encoder. After
// 10 minutes at 0.5 um/min the carriage is 5 um off (exact: no other error).
TEST(BenchDynamics, ThermalDriftGrowsLinearlyInSimulatedTime) {
  sim::bench::BenchSimConfig c = quiet_config();
  c.y.thermal_drift_um_per_min = 0.5;
  sim::bench::BenchDynamics d(c, 0, 0);
  d.advance(300);
  EXPECT_NEAR(d.actual_y_mm(), 0.0025, 1e-9);
  d.advance(300);
  EXPECT_NEAR(d.actual_y_mm(), 0.005, 1e-9);
  EXPECT_DOUBLE_EQ(d.encoder_y_mm(), 0.0);
}

// Residual vibration: from the stop the carriage is displaced by
// A exp(-t / tau) cos(2 pi f t) along the move, while the encoder is already
// in position; a frame taken at 1 tau is off by A e^-1 cos(2 pi f tau), one
// taken after 10 tau by less than A e^-10. Times are the integrator's own
// (time_s of the stop step), so the check is exact to rounding.
TEST(BenchDynamics, ResidualVibrationDecaysAfterTheStop) {
  sim::bench::BenchSimConfig c = quiet_config();
  c.x.vibration_amplitude_mm = 0.02;
  c.x.vibration_frequency_hz = 25;
  c.x.vibration_decay_s = 0.04;
  sim::bench::BenchDynamics d(c, 0, 0);
  d.move(10, 0, 100);
  while (d.moving())
    d.advance(0.25e-3);
  const double stopped_at = d.time_s();
  EXPECT_TRUE(d.in_position());
  EXPECT_GT(d.actual_x_mm() - 10, 0.015);  // just stopped: overshoot of up to A
  d.advance(0.04 - (d.time_s() - stopped_at));
  const double t = 0.04;
  EXPECT_NEAR(d.actual_x_mm() - 10, 0.02 * std::exp(-1.0) * std::cos(2 * M_PI * 25 * t), 1e-6);
  d.advance(0.4);
  EXPECT_LT(std::abs(d.actual_x_mm() - 10), 0.02 * std::exp(-10.0));
  EXPECT_DOUBLE_EQ(d.encoder_x_mm(), 10.0);
}

}  // namespace
