// rig calibrate on a paper-sized calibration sweep (target: at most 10 s on a
// 2-core machine like CI's): the paper's 1,939 positions (7 rows x 277
// distances over the simulated bench's travel), 3 frames each, the paper's
// A4 target (4 markers), ~46 corners per position (~90,000 corners), 0.1 px corner noise,
// written once through the run store.
//  - BM_Calibrate: the bundle adjustment with the rank check and the
//    covariance clustered by position (what rig calibrate reports), 2
//    threads. A run with saved frames adds their detection and a second
//    solve (rig::calibrate::redetected), not measured here.
//  - BM_HeldOutCheck: the second solve on the even positions and the prediction.
// Run: scripts/bench bench_calibrate   (or build-*/tests/bench/bench_calibrate)
#include <benchmark/benchmark.h>
#include <stdlib.h>

#include <filesystem>
#include <string>

#include "rig/calibrate/calibration.hpp"
#include "synthetic_calibration.hpp"

namespace {

const rig::calibrate::CalibrationProblem& paper_problem() {
  static const rig::calibrate::CalibrationProblem problem = [] {
    std::string dir = (std::filesystem::temp_directory_path() / "rig-bench-XXXXXX").string();
    if (mkdtemp(dir.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    const std::string db = dir + "/calibration.db";
    rig_test::SyntheticCalibrationSpec spec;
    spec.true_camera = rig_test::calibration_true_camera();
    spec.true_geometry = rig_test::calibration_true_geometry();
    spec.nominal_rig_toml = rig_test::calibration_nominal_rig_toml();
    spec.frames_per_position = 3;
    for (int row = 0; row < 7; ++row)
      for (int c = 0; c < 277; ++c) {
        const int column = row % 2 == 0 ? c : 276 - c;
        spec.plan.emplace_back(800.0 * column / 276.0, 300.0 * row / 6.0);
      }
    const std::int64_t run = rig_test::write_calibration_run(db, spec);
    rig::calibrate::CalibrationProblem p = rig::calibrate::read_run(db, run);
    std::filesystem::remove_all(dir);
    return p;
  }();
  return problem;
}

void BM_Calibrate(benchmark::State& state) {
  const rig::calibrate::CalibrationProblem& problem = paper_problem();
  for (auto _ : state) {
    const rig::calibrate::CalibrationResult r =
        rig::calibrate::calibrate(problem, rig::calibrate::CalibrationOptions{});
    benchmark::DoNotOptimize(r.rms_px);
    state.counters["corners"] = static_cast<double>(r.corners);
    state.counters["iterations"] = r.iterations;
  }
}
BENCHMARK(BM_Calibrate)->Unit(benchmark::kSecond)->Iterations(1);

void BM_HeldOutCheck(benchmark::State& state) {
  const rig::calibrate::CalibrationProblem& problem = paper_problem();
  for (auto _ : state) {
    const rig::calibrate::HeldOutCheck h =
        rig::calibrate::held_out_check(problem, rig::calibrate::CalibrationOptions{});
    benchmark::DoNotOptimize(h.held_out_rms_px);
  }
}
BENCHMARK(BM_HeldOutCheck)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
