// Modbus benchmarks on loopback:
//  - round trip of one status + position read (the read wait_settled polls),
//    through ModbusBench, through bare libmodbus, and against the pymodbus
//    drive emulator, as median and p99 per transaction;
//  - move_to -> settled for a 1 mm step on the simulated bench at its default
//    dynamics (50 mm/s, 500 mm/s^2: a 89 ms triangular profile) and time
//    scale 1, plus the profile's 20 ms settle time and polling.
// Run: scripts/bench bench_modbus
#include <benchmark/benchmark.h>
#include <modbus/modbus.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "motion/drive_profile.hpp"
#include "motion/modbus_bench.hpp"
#include "sim/bench/config.hpp"
#include "sim/bench/server.hpp"

namespace {

using Clock = std::chrono::steady_clock;

const std::string kSimFile = std::string(RIG_SOURCE_DIR) + "/config/benches/sim.toml";

std::unique_ptr<sim::bench::BenchServer> start_sim() {
  auto server = std::make_unique<sim::bench::BenchServer>(
      motion::load_drive_profile(kSimFile), sim::bench::load_bench_sim_config(kSimFile));
  server->start();
  return server;
}

// Times every iteration of `op` and reports the median and p99, µs.
template <class Op>
void timed_loop(benchmark::State& state, Op op) {
  std::vector<double> us;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    op();
    us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
  }
  std::sort(us.begin(), us.end());
  state.counters["median_us"] = us[us.size() / 2];
  state.counters["p99_us"] = us[std::min(us.size() - 1, us.size() * 99 / 100)];
}

void BM_ModbusBenchStatusRoundTrip(benchmark::State& state) {
  auto server = start_sim();
  motion::ModbusBench bench(motion::BenchUrl::parse(server->url()),
                            motion::load_drive_profile(kSimFile));
  timed_loop(state, [&] { benchmark::DoNotOptimize(bench.status()); });
}
BENCHMARK(BM_ModbusBenchStatusRoundTrip)->UseRealTime();

void BM_LibmodbusReadRoundTrip(benchmark::State& state) {
  auto server = start_sim();
  modbus_t* ctx = modbus_new_tcp("127.0.0.1", server->port());
  if (modbus_connect(ctx) == -1) {
    state.SkipWithError("connect failed");
    return;
  }
  std::uint16_t regs[6];
  timed_loop(state,
             [&] { benchmark::DoNotOptimize(modbus_read_input_registers(ctx, 0, 6, regs)); });
  modbus_close(ctx);
  modbus_free(ctx);
}
BENCHMARK(BM_LibmodbusReadRoundTrip)->UseRealTime();

void BM_PymodbusReadRoundTrip(benchmark::State& state) {
  rig_test::ChildProcess drive(
      {"/usr/bin/python3", std::string(RIG_SOURCE_DIR) + "/tests/motion/pymodbus_drive.py", "0"});
  const auto line = drive.read_line(std::chrono::seconds(10));
  if (!line || line->rfind("PORT ", 0) != 0) {
    state.SkipWithError("pymodbus emulator did not start");
    return;
  }
  modbus_t* ctx = modbus_new_tcp("127.0.0.1", std::stoi(line->substr(5)));
  if (modbus_connect(ctx) == -1) {
    state.SkipWithError("connect failed");
    return;
  }
  std::uint16_t regs[6];
  timed_loop(state, [&] { benchmark::DoNotOptimize(modbus_read_registers(ctx, 512, 6, regs)); });
  modbus_close(ctx);
  modbus_free(ctx);
}
BENCHMARK(BM_PymodbusReadRoundTrip)->UseRealTime();

void BM_MoveToSettled1mm(benchmark::State& state) {
  auto server = start_sim();  // time scale 1, default dynamics
  motion::ModbusBench bench(motion::BenchUrl::parse(server->url()),
                            motion::load_drive_profile(kSimFile));
  bench.home();
  bench.wait_settled(std::chrono::seconds(30));
  double x = 10;
  bench.move_to(x, 10);
  bench.wait_settled(std::chrono::seconds(10));
  timed_loop(state, [&] {
    x = x == 10 ? 11 : 10;
    bench.move_to(x, 10);
    bench.wait_settled(std::chrono::seconds(10));
  });
}
BENCHMARK(BM_MoveToSettled1mm)->UseRealTime()->Unit(benchmark::kMillisecond)->Iterations(40);

}  // namespace

BENCHMARK_MAIN();
