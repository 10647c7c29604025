// Run database benchmarks:
//  - positions appended per second, each position a sweep's worth of rows:
//    2 frames x (4 detections + 10 solvers x 2 scopes estimates) plus stage
//    times, one transaction per position, on a file in /tmp; with durable
//    commits (synchronous FULL: one WAL fsync per position) and without
//    (synchronous NORMAL). Median and p99 per position, rates of positions and
//    of estimate rows (target: >= 100,000 estimate rows per second).
//  - reading one solver's estimates of a 1,000-position run (a report's query).
// Run: scripts/bench bench_store
#include <benchmark/benchmark.h>
#include <stdlib.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "db/store/store.hpp"

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kFrames = 2, kMarkers = 4, kSolvers = 10, kScopes = 2;
constexpr int kEstimatesPerPosition = kFrames * kSolvers * kScopes;

class ScratchDir {
 public:
  ScratchDir() {
    std::string pattern = "/tmp/rig-bench-store-XXXXXX";
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~ScratchDir() { std::filesystem::remove_all(path_); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

db::store::RunDescription run_description() {
  db::store::RunDescription d;
  d.config_json = R"({"frames_per_position":2})";
  d.plan_json = R"({"kind":"grid"})";
  d.plan_size = 100'000'000;
  d.library_versions_json = "{}";
  return d;
}

db::store::PositionRecord position(std::int64_t plan_index) {
  db::store::PositionRecord p;
  p.plan_index = plan_index;
  p.commanded_x_mm = 0.1 * plan_index;
  p.measured_x_mm = p.commanded_x_mm + 0.002;
  p.measured_y_mm = 0;
  p.true_distance_m = 0.5;
  p.stage_times = {{"move", 0.4}, {"settle", 0.1}, {"capture", 0.03}, {"detect", 0.004}};
  for (int f = 0; f < kFrames; ++f) {
    db::store::FrameRecord frame;
    frame.index = f;
    frame.host_timestamp_ns = 1'700'000'000'000'000'000LL + plan_index;
    frame.source = "sim";
    for (int m = 0; m < kMarkers; ++m) {
      db::store::DetectionRecord d;
      d.marker_id = m;
      for (int c = 0; c < 8; ++c)
        d.corners_px[c] = 100.0 + 17.0 * c + m;
      frame.detections.push_back(d);
    }
    for (int s = 0; s < kSolvers; ++s) {
      for (const char* scope : {"0", "target"}) {
        db::store::EstimateRecord e;
        e.solver = "solver_" + std::to_string(s);
        e.scope = scope;
        e.R_cam_target = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        e.t_cam_target_m = {0.01, -0.02, 0.5};
        e.distance_m = std::sqrt(0.01 * 0.01 + 0.02 * 0.02 + 0.25);
        e.reprojection_error_px = 0.4;
        e.generalization_error_px = 10.0;
        e.iterations = 5;
        e.converged = true;
        e.termination = "converged";
        e.time_us = 100;
        frame.estimates.push_back(e);
      }
    }
    p.frames.push_back(frame);
  }
  return p;
}

void BM_AppendPosition(benchmark::State& state) {
  ScratchDir dir;
  db::store::StoreOptions options;
  options.durable_commits = state.range(0) != 0;
  db::store::Store store(dir.file("bench.db"), options);
  const std::int64_t run = store.start_run(run_description());
  db::store::PositionRecord p = position(0);
  std::vector<double> us;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    store.append_position(run, p);
    us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
    ++p.plan_index;
  }
  std::sort(us.begin(), us.end());
  const double median_us = us[us.size() / 2];
  state.counters["median_us"] = median_us;
  state.counters["p99_us"] = us[std::min(us.size() - 1, us.size() * 99 / 100)];
  state.counters["positions_per_s_median"] = 1e6 / median_us;
  state.counters["estimate_rows_per_s_median"] = kEstimatesPerPosition * 1e6 / median_us;
  state.SetItemsProcessed(state.iterations());  // positions per second, mean
}
BENCHMARK(BM_AppendPosition)->ArgName("durable")->Arg(1)->Arg(0)->UseRealTime();

void BM_ReadOneSolversEstimates(benchmark::State& state) {
  ScratchDir dir;
  db::store::StoreOptions options;
  options.durable_commits = false;  // setup speed only; reads do not depend on it
  db::store::Store store(dir.file("bench.db"), options);
  const std::int64_t run = store.start_run(run_description());
  constexpr int kPositions = 1000;
  for (int i = 0; i < kPositions; ++i)
    store.append_position(run, position(i));
  std::size_t rows = 0;
  for (auto _ : state) {
    rows = store.estimates(run, "solver_3").size();
    benchmark::DoNotOptimize(rows);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(rows));
  state.counters["rows"] = static_cast<double>(rows);
}
BENCHMARK(BM_ReadOneSolversEstimates)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
