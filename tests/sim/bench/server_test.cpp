// The simulated bench as a server: several clients, the actual position the
// camera sees versus the read-back the driver sees, time scale, prompt stop,
// and its [sim] configuration.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "motion/errors.hpp"
#include "sim_bench_fixture.hpp"

namespace {

using namespace std::chrono_literals;
using rig_test::SimBenchTest;
using Clock = std::chrono::steady_clock;

class BenchServer : public SimBenchTest {};

TEST_F(BenchServer, ServesSeveralClientsAtOnce) {
  auto mover = homed_bench();
  mover->move_to(50, 50);
  std::atomic<int> failures{0};
  std::vector<std::thread> readers;
  for (int i = 0; i < 4; ++i) {
    readers.emplace_back([&] {
      try {
        auto bench = connect();
        for (int k = 0; k < 200; ++k)
          bench->status();
      } catch (const motion::BenchError&) {
        ++failures;
      }
    });
  }
  const motion::BenchStatus s = mover->wait_settled(5s);
  for (std::thread& t : readers)
    t.join();
  EXPECT_EQ(failures, 0);
  EXPECT_NEAR(s.position.x_mm, 50, 1e-9);
  EXPECT_GE(server_->requests(), 800u);
}

TEST_F(BenchServer, ActualPositionCarriesTheBacklashTheEncoderDoesNotSee) {
  sim_.x.backlash_mm = 0.02;
  auto bench = homed_bench();
  bench->move_to(10, 0);
  bench->wait_settled(5s);
  bench->move_to(5, 0);
  const motion::BenchStatus s = bench->wait_settled(5s);
  // The driver reads the motor's encoder: exactly the target.
  EXPECT_NEAR(s.position.x_mm, 5, 1e-9);
  // After a move in -x the carriage lags the motor by half the deadband.
  EXPECT_NEAR(server_->actual_position_mm().x_mm, 5.01, 1e-9);
}

TEST_F(BenchServer, ActualPositionCarriesTheRepeatabilityError) {
  sim_.x.repeatability_mm = sim_.y.repeatability_mm = 0.005;
  auto bench = homed_bench();
  bench->move_to(10, 10);
  bench->wait_settled(5s);
  const motion::XY actual = server_->actual_position_mm();
  // A normal error of 5 µm sigma: non-zero, and inside 6 sigma. The draw
  // comes from the [sim] seed, so it is the same every run; another seed
  // would fall outside with probability 2e-9 per axis.
  EXPECT_NE(actual.x_mm, 10);
  EXPECT_NEAR(actual.x_mm, 10, 0.03);
  EXPECT_NEAR(actual.y_mm, 10, 0.03);
  EXPECT_NEAR(bench->position().x_mm, 10, 1e-9);
}

TEST_F(BenchServer, ActualPositionCanBeReadFromAnotherThreadDuringAMove) {
  // The 100 mm move lasts 1.05 s of wall time at time scale 2: ten readings
  // inside it need the reader, which asks for 1 ms sleeps, to wake once every
  // 100 ms on average, however loaded the host.
  sim_.time_scale = 2;
  auto bench = homed_bench();
  std::atomic<bool> done{false};
  std::vector<double> xs;
  std::thread camera([&] {
    while (!done) {
      xs.push_back(server_->actual_position_mm().x_mm);
      std::this_thread::sleep_for(1ms);
    }
  });
  bench->move_to(100, 0);
  bench->wait_settled(5s);
  done = true;
  camera.join();
  EXPECT_GE(std::count_if(xs.begin(), xs.end(), [](double x) { return x > 0 && x < 100; }), 10);
  // A monotonic move seen as a monotonic sequence, ending on the target.
  for (size_t i = 1; i < xs.size(); ++i)
    EXPECT_GE(xs[i], xs[i - 1]);
  EXPECT_NEAR(xs.back(), 100, 1e-9);
}

TEST_F(BenchServer, TimeScaleRunsTheSameMoveFaster) {
  // 100 mm at 50 mm/s and 500 mm/s^2: 2.1 s of simulated time; at time
  // scale 10 it takes 0.21 s of wall time plus polling and settle time. The
  // physics runs on the wall clock, so it cannot be faster than 0.21 s; in
  // real time it would take 2.1 s, so under 2 s shows the scale applied and
  // leaves 1.8 s for a loaded host's polling.
  auto bench = homed_bench();
  const auto t0 = Clock::now();
  bench->move_to(100, 0);
  bench->wait_settled(10s);
  const double wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_GT(wall_s, 0.2);
  EXPECT_LT(wall_s, 2.0);
}

TEST_F(BenchServer, StopsPromptlyWithClientsConnectedAndAStallPending) {
  auto bench = homed_bench();
  sim::bench::FaultPlan faults;
  faults.stall_after_requests = 1;
  faults.stall_s = 10;
  const std::uint64_t before = server_->requests();
  server_->inject(faults);
  std::thread stalled([&] { EXPECT_THROW(bench->status(), motion::BenchError); });
  // Stop once the server holds the request that started the stall.
  const auto patience = Clock::now() + 10s;
  while (server_->requests() == before && Clock::now() < patience)
    std::this_thread::sleep_for(1ms);
  ASSERT_GT(server_->requests(), before);
  const auto t0 = Clock::now();
  server_->stop();
  // Prompt: a stop that waited for the stall would take 10 s; 5 s leaves
  // seconds for a loaded host to schedule the two threads it joins.
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 5.0);
  stalled.join();
}

TEST(BenchSimConfig, ShippedSimTableLoads) {
  const sim::bench::BenchSimConfig c =
      sim::bench::load_bench_sim_config(rig_test::sim_profile_path());
  EXPECT_EQ(c.time_scale, 1.0);
  EXPECT_EQ(c.x.accel_mm_s2, 500);
  EXPECT_EQ(c.y.travel_max_mm, 305);
  EXPECT_TRUE(c.require_homing);
  EXPECT_FALSE(c.faults.alarm_at.has_value());
}

TEST(BenchSimConfig, FaultsAreReadFromTheFile) {
  const sim::bench::BenchSimConfig c = sim::bench::parse_bench_sim_config(
      "[sim.faults]\ndrop_after_requests = 7\n"
      "alarm_at = { x_mm = 100.0, y_mm = 50.0, radius_mm = 1.0, code = 2 }\n",
      "f.toml");
  EXPECT_EQ(c.faults.drop_after_requests, 7);
  ASSERT_TRUE(c.faults.alarm_at.has_value());
  EXPECT_EQ(c.faults.alarm_at->x_mm, 100);
  EXPECT_EQ(c.faults.alarm_at->code, 2);
}

TEST(BenchSimConfig, AnInitialPositionOutsideTheTravelIsRefusedNamingTheDefault) {
  try {
    sim::bench::parse_bench_sim_config("[sim.y]\ntravel_min_mm = 10\n", "f.toml");
    FAIL();
  } catch (const motion::ProfileError& e) {
    EXPECT_STREQ(e.what(),
                 "f.toml: sim.y.initial_mm: not given, so 0 mm; expected a position within the "
                 "travel 10..505 mm");
  }
}

TEST(BenchSimConfig, MisspeltKeyIsRefusedByName) {
  try {
    sim::bench::parse_bench_sim_config("[sim.x]\naccel_mm_s = 5\n", "f.toml");
    FAIL();
  } catch (const motion::ProfileError& e) {
    EXPECT_STREQ(e.what(),
                 "f.toml: sim.x.accel_mm_s = 5: unknown key (misspelt?); expected one of "
                 "max_speed_mm_s, accel_mm_s2, travel_min_mm, travel_max_mm, backlash_mm, "
                 "repeatability_mm, initial_mm, encoder_scale_ppm, thermal_drift_um_per_min, "
                 "vibration_amplitude_mm, vibration_frequency_hz, vibration_decay_s");
  }
}

}  // namespace
