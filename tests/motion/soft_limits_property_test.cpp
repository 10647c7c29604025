// Property: over thousands of random commands against random profiles (word
// order, units, register layout, feedback table, soft limits), no position
// outside the soft limits is ever written to the drive. The simulated bench
// records every target written to it; that record is checked, not the
// driver's own view.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "motion/errors.hpp"
#include "motion/modbus_bench.hpp"
#include "sim/bench/server.hpp"

namespace {

motion::DriveProfile random_profile(std::mt19937_64& rng) {
  auto uniform = [&](double a, double b) {
    return std::uniform_real_distribution<double>(a, b)(rng);
  };
  motion::DriveProfile p;
  p.source = "random profile";
  p.name = "random";
  p.word_order = rng() % 2 ? motion::WordOrder::kHighFirst : motion::WordOrder::kLowFirst;
  const double counts[] = {1, 10, 100, 1000, 1234.5, 4000};
  p.counts_per_mm = counts[rng() % 6];
  p.speed_units_per_mm_s = rng() % 2 ? 1 : 100;
  p.position_tolerance_mm = 2 / p.counts_per_mm;
  // Fields in shuffled 2-register slots starting at a random base.
  std::vector<int> slots(8);
  std::iota(slots.begin(), slots.end(), 0);
  std::shuffle(slots.begin(), slots.end(), rng);
  const int base = static_cast<int>(rng() % 1000);
  auto at = [&](int i) { return base + 2 * slots[i]; };
  p.registers.target_x = at(0);
  p.registers.target_y = at(1);
  p.registers.speed = at(2);
  p.registers.command = at(3);
  p.registers.feedback =
      rng() % 2 ? motion::RegisterTable::kInput : motion::RegisterTable::kHolding;
  p.registers.actual_x = at(4);
  p.registers.actual_y = at(5);
  p.registers.status = at(6);
  p.registers.alarm = at(7);
  // Limits of any sign and size, up to +-100 m (well inside int32 counts).
  const double scale = std::pow(10.0, uniform(0, 5));
  p.soft_limits.x_min_mm = uniform(-scale, scale);
  p.soft_limits.x_max_mm = p.soft_limits.x_min_mm + uniform(1, scale);
  p.soft_limits.y_min_mm = uniform(-scale, scale);
  p.soft_limits.y_max_mm = p.soft_limits.y_min_mm + uniform(1, scale);
  p.home_x_mm = p.soft_limits.x_min_mm;
  p.home_y_mm = p.soft_limits.y_min_mm;
  p.timing.response_timeout_ms = 200;
  motion::validate(p);
  return p;
}

// A target near the limits: inside, outside, exactly on, within a fraction
// of a count of them, or not a number at all.
double random_coordinate(std::mt19937_64& rng, double lo, double hi, double count_mm) {
  auto uniform = [&](double a, double b) {
    return std::uniform_real_distribution<double>(a, b)(rng);
  };
  const double span = hi - lo;
  switch (rng() % 8) {
    case 0:
      return lo;
    case 1:
      return hi;
    case 2:
      return hi + uniform(-count_mm, count_mm);
    case 3:
      return lo + uniform(-count_mm, count_mm);
    case 4:
      return std::numeric_limits<double>::quiet_NaN();
    case 5:
      return (rng() % 2 ? 1 : -1) * std::numeric_limits<double>::infinity();
    case 6:
      return uniform(lo - 1e9, hi + 1e9);
    default:
      return uniform(lo - span, hi + span);
  }
}

TEST(SoftLimitsProperty, NoPositionOutsideTheSoftLimitsIsEverWritten) {
  std::mt19937_64 rng(20260522);
  const int profiles = 50, commands = 200;  // 10,000 commands
  int accepted = 0, refused = 0;
  for (int k = 0; k < profiles; ++k) {
    const motion::DriveProfile p = random_profile(rng);
    sim::bench::BenchSimConfig sim_config;
    sim_config.require_homing = false;
    sim_config.time_scale = 50;
    for (sim::bench::AxisConfig* a : {&sim_config.x, &sim_config.y}) {
      a->travel_min_mm = -1e9;  // the drive would go anywhere: only the driver protects
      a->travel_max_mm = 1e9;
      a->initial_mm = 0;
    }
    sim::bench::BenchServer server(p, sim_config);
    server.start();
    motion::ModbusBench bench(motion::BenchUrl::parse(server.url()), p);
    const double count_mm = 1 / p.counts_per_mm;
    int accepted_here = 0;
    for (int i = 0; i < commands; ++i) {
      const int kind = static_cast<int>(rng() % 10);
      if (kind == 0) {
        bench.stop();
        continue;
      }
      const double x =
          random_coordinate(rng, p.soft_limits.x_min_mm, p.soft_limits.x_max_mm, count_mm);
      const double y =
          random_coordinate(rng, p.soft_limits.y_min_mm, p.soft_limits.y_max_mm, count_mm);
      const bool inside = p.soft_limits.contains(x, y);  // false for NaN
      try {
        bench.move_to(x, y);
        EXPECT_TRUE(inside) << "accepted (" << x << ", " << y << ")";
        ++accepted_here;
      } catch (const motion::SoftLimitError&) {
        EXPECT_FALSE(inside) << "refused (" << x << ", " << y << ")";
        ++refused;
      }
    }
    // Per axis: the two axes' registers may be written by separate requests.
    int x_writes = 0, y_writes = 0;
    for (const auto& w : server.written_targets()) {
      if (w.x_mm) {
        ++x_writes;
        ASSERT_TRUE(*w.x_mm >= p.soft_limits.x_min_mm && *w.x_mm <= p.soft_limits.x_max_mm)
            << "profile " << k << " wrote x " << *w.x_mm << " outside [" << p.soft_limits.x_min_mm
            << ", " << p.soft_limits.x_max_mm << "]";
      }
      if (w.y_mm) {
        ++y_writes;
        ASSERT_TRUE(*w.y_mm >= p.soft_limits.y_min_mm && *w.y_mm <= p.soft_limits.y_max_mm)
            << "profile " << k << " wrote y " << *w.y_mm << " outside [" << p.soft_limits.y_min_mm
            << ", " << p.soft_limits.y_max_mm << "]";
      }
    }
    EXPECT_EQ(x_writes, accepted_here);
    EXPECT_EQ(y_writes, accepted_here);
    accepted += accepted_here;
  }
  // Both branches were exercised in earnest.
  EXPECT_GT(accepted, 1000);
  EXPECT_GT(refused, 1000);
}

}  // namespace
