// Sweep benchmarks: what one bench position costs the
// controller once the bench has settled and the frames are in hand, i.e.
// everything of rig::sweep::Controller's measure_position and append_position except
// motion, settling and exposure (rig/sweep/src/controller.cpp):
//   per frame  vision::FrameMeasurer::measure (detector + every solver of the
//              registry on the pose marker's scope and on the target's scope)
//              and rig::sweep::to_frame_record;
//   per position  rig::sweep::ground_truth_at (true pose, viewing angle, visible
//              markers, Cramér-Rao bounds) and, for the *Store benchmarks,
//              db::store::Store::append_position into a SQLite file in /tmp with
//              record_store_time on, as a sweep opens it.
//
// Frames: the simulated rig as `rig sim --config config/sim.toml` renders it
// (paper camera, config/targets/paper.toml, config/rigs/sim.toml), at bench
// positions x = 0, 100, ..., 500 mm, y = 150 mm (1.00 m down to 0.50 m, where
// all four markers are in view: checked), rendered once before timing. The
// frames of a position are cycled, so a run of many positions repeats them.
//
// Frames are measured by the product's rig::sweep::FramePool with T threads
// (the sweep file's [compute] threads): T = 1 is the serial path (every frame
// measured on the benchmark's thread); T > 1 measures the frames of a
// position in parallel, as the controller does; ahead = 1 also hands the
// next position's frames to the pool before this position's records are
// built and stored, as the controller does for a replay
// (SweepConfig::acquire_ahead). The records are the same either way.
//
// Benchmarks (positions per second = items_per_second; target: >= 100
// with 4 markers and every solver; with 2 threads, ahead, durable, 3 frames:
// >= 600, and read as the ratio to threads:1 in the same run):
//   BM_PositionCompute/frames:F/threads:T/ahead:A
//                                          measure + to_frame_record for F frames,
//                                          ground truth once
//   BM_PositionComputeAndStore/frames:F/durable:D/threads:T/ahead:A
//                                          the same + append_position;
//                                          durable = StoreOptions::durable_commits
//                                          (config/sweeps/ci.toml: true)
//   Counters per position (ms): detect_ms, solve_ms (every solver, both scopes,
//   all frames; wall times inside measure, so with T > 1 they include the
//   threads' contention), truth_ms, record_ms (to_frame_record), store_ms
//   (append_position, commit included); markers_per_frame (detected);
//   positions_per_s_median (1 / the median time between two positions done);
//   cpu_ms (CPU time of every thread of the process, user + system, per
//   position: with T threads on T cores, T x the wall time per position when
//   no core ever waits; T = 1 leaves OpenCV's own parallel loops on, so there
//   it can exceed the wall time).
//   BM_EstimateInsertRate/durable:D       append_position of a real 3-frame
//                                          position (4 detections, 10 solvers x
//                                          2 scopes per frame = 60 estimate
//                                          rows), estimate_rows_per_s (target:
//                                          >= 100,000 per second)
//   BM_ResidentMemory10k                   10,000 positions of compute + store
//                                          (1 frame each to keep it near a
//                                          minute, durable commits), VmRSS
//                                          sampled after positions 100, 200,
//                                          500, 1000, 2000, ..., 10000:
//                                          rss_mb_at_N, rss_growth_mb (10000
//                                          minus 100; target: flat) and
//                                          rss_growth_mb_from_1000; SQLite's own
//                                          heap (page cache included) at 100 and
//                                          10000 (sqlite_heap_mb_at_N).
// Run: scripts/bench bench_sweep, or
//   build/tests/bench/bench_sweep --benchmark_filter='Position|Insert'
//   build/tests/bench/bench_sweep --benchmark_filter=ResidentMemory
#include <benchmark/benchmark.h>
#include <sqlite3.h>
#include <stdlib.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "db/store/store.hpp"
#include "rig/sweep/controller.hpp"
#include "rig/sweep/frame_pool.hpp"
#include "rig/sweep/ground_truth.hpp"
#include "sim/scene/renderer.hpp"
#include "vision/camera.hpp"
#include "vision/codebook.hpp"
#include "vision/frame_measurement.hpp"
#include "vision/rig_geometry.hpp"
#include "vision/target.hpp"
#include "vision/timing.hpp"

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kMaxFramesPerPosition = 3;  // config/sweeps/ci.toml
constexpr double kBenchY_mm = 150.0;      // config/rigs/sim.toml: the camera faces the pose marker
const double kBenchX_mm[] = {0.0, 100.0, 200.0, 300.0, 400.0, 500.0};

struct BenchPosition {
  double x_mm = 0, y_mm = 0;
  std::vector<cv::Mat> frames;  // kMaxFramesPerPosition images
};

struct SimulatedRig {
  vision::Camera camera = vision::Camera::paper_default();
  vision::Target target =
      vision::Target::load(std::string(RIG_SOURCE_DIR) + "/config/targets/paper.toml");
  vision::RigGeometry geometry =
      vision::RigGeometry::load(std::string(RIG_SOURCE_DIR) + "/config/rigs/sim.toml");
  std::vector<BenchPosition> positions;
};

// Renders the frames of every bench position once. Throws std::runtime_error
// if the geometry does not put all four markers in view at one of them (the
// benchmark is specified with 4 markers).
const SimulatedRig& simulated_rig() {
  static const SimulatedRig* rig = [] {
    auto* r = new SimulatedRig;
    const sim::scene::SceneRenderer renderer(r->camera, r->target, vision::Codebook());
    std::uint64_t seed = 1;  // config/sim.toml: frame k's noise from seed + k
    for (double x : kBenchX_mm) {
      const rig::sweep::GroundTruth truth =
          rig::sweep::ground_truth_at(r->geometry, r->camera, r->target, x, kBenchY_mm);
      if (truth.visible_markers.size() != r->target.markers.size())
        throw std::runtime_error(
            "bench position x = " + std::to_string(x) + " mm, y = " + std::to_string(kBenchY_mm) +
            " mm shows " + std::to_string(truth.visible_markers.size()) +
            " markers; expected all " + std::to_string(r->target.markers.size()));
      BenchPosition p{x, kBenchY_mm, {}};
      const vision::Pose pose = r->geometry.T_cam_target(x, kBenchY_mm);
      for (int k = 0; k < kMaxFramesPerPosition; ++k)
        p.frames.push_back(renderer.render(pose, seed++).image);
      r->positions.push_back(std::move(p));
    }
    return r;
  }();
  return *rig;
}

// Median of per-position wall times, seconds: less sensitive than the mean to
// the other processes of a shared machine.
double median(std::vector<double> seconds) {
  if (seconds.empty()) return 0;
  std::nth_element(seconds.begin(), seconds.begin() + seconds.size() / 2, seconds.end());
  return seconds[seconds.size() / 2];
}

// Seconds spent per stage, summed over the positions measured.
struct StageSums {
  double detect = 0, solve = 0, truth = 0, record = 0, store = 0;
  std::int64_t frames = 0, detections = 0;
  std::vector<double> position_s;  // wall time of each whole position
  double process_cpu_s = 0;        // CPU time of every thread of the process
};

// CPU time of every thread of the process so far (user + system), seconds.
double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  const auto s = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * t.tv_usec; };
  return s(u.ru_utime) + s(u.ru_stime);
}

// A position whose frames are in the pool: what the controller's acquire
// leaves for finish (rig/sweep/src/controller.cpp).
struct AcquiredPosition {
  std::int64_t plan_index = 0;
  std::vector<rig::sweep::FramePool::Ticket> frames;
};

// The position's frames handed to the pool, as the controller's capture does.
AcquiredPosition acquire_position(rig::sweep::FramePool& pool, const SimulatedRig& rig,
                                  std::int64_t plan_index, int frames_per_position) {
  const BenchPosition& p =
      rig.positions[static_cast<std::size_t>(plan_index) % rig.positions.size()];
  AcquiredPosition a{plan_index, {}};
  for (int k = 0; k < frames_per_position; ++k)
    a.frames.push_back(pool.submit(p.frames[static_cast<std::size_t>(k)]));
  return a;
}

// What the controller's finish builds from an acquired position: the truth,
// each frame's measurement taken in frame order and its record.
db::store::PositionRecord finish_position(rig::sweep::FramePool& pool, const SimulatedRig& rig,
                                          AcquiredPosition& a, StageSums& sums) {
  const BenchPosition& p =
      rig.positions[static_cast<std::size_t>(a.plan_index) % rig.positions.size()];
  db::store::PositionRecord rec;
  rec.plan_index = a.plan_index;
  rec.commanded_x_mm = p.x_mm;
  rec.commanded_y_mm = p.y_mm;
  rec.measured_x_mm = p.x_mm;
  rec.measured_y_mm = p.y_mm;
  rec.stage_times = {{"move", 0}, {"settle", 0}, {"capture", 0}};

  const auto truth_start = Clock::now();
  const rig::sweep::GroundTruth truth =
      rig::sweep::ground_truth_at(rig.geometry, rig.camera, rig.target, p.x_mm, p.y_mm);
  rec.true_distance_m = truth.distance_m;
  rec.true_viewing_angle_deg = truth.viewing_angle_deg;
  rec.visible_markers = truth.visible_markers;
  rec.distance_bounds = truth.distance_bounds;
  sums.truth += vision::seconds_since(truth_start);

  double detect_s = 0;
  std::map<std::string, double> solve_s;
  for (std::size_t k = 0; k < a.frames.size(); ++k) {
    const vision::FrameMeasurement m = pool.take(a.frames[k]);
    detect_s += m.primary().detect_s;
    for (const auto& [name, s] : m.primary().solve_s) {
      solve_s[name] += s;
      sums.solve += s;
    }
    sums.detections += static_cast<std::int64_t>(m.primary().detections.size());
    const auto record_start = Clock::now();
    db::store::FrameRecord f = rig::sweep::to_frame_record(m, static_cast<int>(k));
    f.host_timestamp_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                              std::chrono::system_clock::now().time_since_epoch())
                              .count();
    f.source = "gige:rig-rig-sim-RIGSIM01";
    rec.frames.push_back(std::move(f));
    sums.record += vision::seconds_since(record_start);
  }
  sums.detect += detect_s;
  sums.frames += static_cast<std::int64_t>(a.frames.size());
  rec.stage_times.push_back({"detect", detect_s});
  for (const auto& name : pool.measurer().solver_names())
    rec.stage_times.push_back({"solve:" + name, solve_s[name]});
  rec.status = db::store::PositionStatus::kOk;
  return rec;
}

// One position, serially: acquired and finished.
db::store::PositionRecord measure_position(rig::sweep::FramePool& pool, const SimulatedRig& rig,
                                           std::int64_t plan_index, int frames_per_position,
                                           StageSums& sums) {
  AcquiredPosition a = acquire_position(pool, rig, plan_index, frames_per_position);
  return finish_position(pool, rig, a, sums);
}

class ScratchDir {
 public:
  ScratchDir() {
    std::string pattern = "/tmp/rig-bench-sweep-XXXXXX";
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed in /tmp");
    path_ = pattern;
  }
  ~ScratchDir() { std::filesystem::remove_all(path_); }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

// A store opened as `rig sweep` opens it, with one running run.
struct SweepStore {
  ScratchDir dir;
  db::store::Store store;
  std::int64_t run_id;

  explicit SweepStore(bool durable_commits)
      : store(dir.file("run.db"), options(durable_commits)),
        run_id(store.start_run(description())) {}

  static db::store::StoreOptions options(bool durable_commits) {
    db::store::StoreOptions o;
    o.durable_commits = durable_commits;
    o.record_store_time = true;
    return o;
  }
  static db::store::RunDescription description() {
    db::store::RunDescription d;
    d.config_json = R"({"frames_per_position":3})";
    d.plan_json = R"({"kind":"grid"})";
    d.plan_size = 1'000'000'000;
    d.library_versions_json = "{}";
    return d;
  }
};

// Stage counters per position (ms) and the positions-per-second rates, for
// `positions` positions measured in the benchmark's time.
void report_stages(benchmark::State& state, const StageSums& sums, std::int64_t positions) {
  const double n = static_cast<double>(positions);
  state.counters["detect_ms"] = 1e3 * sums.detect / n;
  state.counters["solve_ms"] = 1e3 * sums.solve / n;
  state.counters["truth_ms"] = 1e3 * sums.truth / n;
  state.counters["record_ms"] = 1e3 * sums.record / n;
  if (sums.store > 0) state.counters["store_ms"] = 1e3 * sums.store / n;
  state.counters["markers_per_frame"] =
      sums.frames ? static_cast<double>(sums.detections) / static_cast<double>(sums.frames) : 0;
  state.counters["cpu_ms"] = 1e3 * sums.process_cpu_s / n;
  if (!sums.position_s.empty())
    state.counters["positions_per_s_median"] = 1 / median(sums.position_s);
  state.SetItemsProcessed(positions);  // positions per second, mean
}

// One position per iteration, `frames` each, measured by a pool of `threads`;
// with `ahead`, the next position is acquired before this one is finished
// (and stored, when `db` is given). The position acquired last is dropped.
void run_positions(benchmark::State& state, int frames, int threads, bool ahead, SweepStore* db) {
  const SimulatedRig& rig = simulated_rig();
  const vision::FrameMeasurer measurer(rig.camera, rig.target);
  rig::sweep::FramePool pool(measurer, threads);
  StageSums sums;
  std::int64_t next = 0;
  std::optional<AcquiredPosition> pending;
  auto last_done = Clock::now();
  const double cpu_start = process_cpu_seconds();
  for (auto _ : state) {
    if (!pending) pending = acquire_position(pool, rig, next++, frames);
    std::optional<AcquiredPosition> following;
    if (ahead) following = acquire_position(pool, rig, next++, frames);
    const db::store::PositionRecord rec = finish_position(pool, rig, *pending, sums);
    if (db != nullptr) {
      const auto store_start = Clock::now();
      db->store.append_position(db->run_id, rec);
      sums.store += vision::seconds_since(store_start);
    }
    benchmark::DoNotOptimize(rec);
    pending = std::move(following);
    const auto done = Clock::now();
    sums.position_s.push_back(std::chrono::duration<double>(done - last_done).count());
    last_done = done;
  }
  sums.process_cpu_s = process_cpu_seconds() - cpu_start;
  report_stages(state, sums, state.iterations());
}

void BM_PositionCompute(benchmark::State& state) {
  run_positions(state, static_cast<int>(state.range(0)), static_cast<int>(state.range(1)),
                state.range(2) != 0, nullptr);
}
BENCHMARK(BM_PositionCompute)
    ->ArgNames({"frames", "threads", "ahead"})
    ->Args({1, 1, 0})
    ->Args({kMaxFramesPerPosition, 1, 0})
    ->Args({kMaxFramesPerPosition, 2, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_PositionComputeAndStore(benchmark::State& state) {
  SweepStore db(state.range(1) != 0);
  run_positions(state, static_cast<int>(state.range(0)), static_cast<int>(state.range(2)),
                state.range(3) != 0, &db);
}
BENCHMARK(BM_PositionComputeAndStore)
    ->ArgNames({"frames", "durable", "threads", "ahead"})
    ->Args({1, 1, 1, 0})
    ->Args({kMaxFramesPerPosition, 1, 1, 0})
    ->Args({kMaxFramesPerPosition, 1, 2, 0})
    ->Args({kMaxFramesPerPosition, 1, 2, 1})
    ->Args({kMaxFramesPerPosition, 0, 1, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_EstimateInsertRate(benchmark::State& state) {
  const SimulatedRig& rig = simulated_rig();
  const vision::FrameMeasurer measurer(rig.camera, rig.target);
  rig::sweep::FramePool pool(measurer, 1);
  StageSums unused;
  // A real position as the controller stores it, appended under new plan indices.
  db::store::PositionRecord rec = measure_position(pool, rig, 0, kMaxFramesPerPosition, unused);
  std::int64_t estimate_rows = 0, detection_rows = 0;
  for (const auto& f : rec.frames) {
    estimate_rows += static_cast<std::int64_t>(f.estimates.size());
    detection_rows += static_cast<std::int64_t>(f.detections.size());
  }
  SweepStore db(state.range(0) != 0);
  std::vector<double> append_s;
  for (auto _ : state) {
    const auto start = Clock::now();
    db.store.append_position(db.run_id, rec);
    append_s.push_back(vision::seconds_since(start));
    ++rec.plan_index;
  }
  state.counters["estimate_rows_per_s_median"] =
      static_cast<double>(estimate_rows) / median(append_s);
  state.counters["estimate_rows_per_position"] = static_cast<double>(estimate_rows);
  state.counters["detection_rows_per_position"] = static_cast<double>(detection_rows);
  state.counters["estimate_rows_per_s"] = benchmark::Counter(
      static_cast<double>(estimate_rows * state.iterations()), benchmark::Counter::kIsRate);
  state.SetItemsProcessed(state.iterations());  // positions per second
}
BENCHMARK(BM_EstimateInsertRate)
    ->ArgName("durable")
    ->Arg(1)
    ->Arg(0)
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

// VmRSS of this process from /proc/self/status, MiB (Linux).
double resident_mib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // kB
  throw std::runtime_error("no VmRSS line in /proc/self/status");
}

double resident_at(const std::vector<std::pair<std::int64_t, double>>& samples,
                   std::int64_t positions) {
  for (const auto& [done, mib] : samples)
    if (done == positions) return mib;
  throw std::logic_error("no resident memory sample after " + std::to_string(positions));
}

void BM_ResidentMemory10k(benchmark::State& state) {
  constexpr std::int64_t kPositions = 10'000;
  const SimulatedRig& rig = simulated_rig();
  const vision::FrameMeasurer measurer(rig.camera, rig.target);
  rig::sweep::FramePool pool(measurer, 1);
  SweepStore db(/*durable_commits=*/true);
  StageSums sums;
  std::vector<std::pair<std::int64_t, double>> samples;
  double sqlite_heap_at_100 = 0;  // SQLite's own allocations (page cache, statements), MiB
  for (auto _ : state) {
    for (std::int64_t index = 0; index < kPositions; ++index) {
      const db::store::PositionRecord rec = measure_position(pool, rig, index, 1, sums);
      const auto store_start = Clock::now();
      db.store.append_position(db.run_id, rec);
      sums.store += vision::seconds_since(store_start);
      const std::int64_t done = index + 1;
      if (done == 100 || done == 200 || done == 500 || done % 1000 == 0)
        samples.emplace_back(done, resident_mib());
      if (done == 100) sqlite_heap_at_100 = static_cast<double>(sqlite3_memory_used()) / 1048576;
    }
  }
  for (const auto& [done, mib] : samples)
    state.counters["rss_mb_at_" + std::to_string(done)] = mib;
  state.counters["rss_growth_mb"] = samples.back().second - samples.front().second;
  state.counters["rss_growth_mb_from_1000"] = samples.back().second - resident_at(samples, 1000);
  state.counters["sqlite_heap_mb_at_100"] = sqlite_heap_at_100;
  state.counters["sqlite_heap_mb_at_10000"] = static_cast<double>(sqlite3_memory_used()) / 1048576;
  report_stages(state, sums, kPositions * state.iterations());
}
BENCHMARK(BM_ResidentMemory10k)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
