// Per-solve time of every pose solver, ours and OpenCV's, on the same problems
// in one run: a 5 cm marker (4 corners) and a 2x2 sheet (16 corners) seen by
// the paper's camera with distortion at 0.1-1.0 m, 0.5 px corner noise.
//
//   build/tests/bench/bench_solvers --benchmark_repetitions=5
//   --benchmark_report_aggregates_only=true
//
// Each iteration solves the next of 256 pre-drawn problems (correspondences
// prepared beforehand: undistortion is the camera model's, shared by all).
// Counters: iterations per solve, converged fraction.
#include <benchmark/benchmark.h>

#include "synthetic_pose.hpp"
#include "vision/correspondences.hpp"
#include "vision/solvers.hpp"

namespace {

const vision::Camera& camera() {
  static const vision::Camera cam = vision::Camera::paper_default();
  return cam;
}

const std::vector<vision::Correspondences>& problems(bool whole_target) {
  static std::vector<vision::Correspondences> sets[2];
  auto& set = sets[whole_target];
  if (set.empty()) {
    rig_test::ProblemSpec spec;
    spec.noise_px = 0.5;
    spec.whole_target = whole_target;
    std::mt19937_64 rng(7);
    for (int i = 0; i < 256; ++i) {
      const auto p = rig_test::draw_problem(camera(), spec, rng);
      set.push_back(vision::make_correspondences(camera(), p.object_points, p.image_points_px));
    }
  }
  return set;
}

void BM_Solve(benchmark::State& state, const std::string& name, bool whole_target) {
  const auto solver = vision::make_solver(name);
  const auto& set = problems(whole_target);
  size_t i = 0;
  double iterations = 0, converged = 0, solves = 0;
  for (auto _ : state) {
    const vision::Estimate e = solver->solve(set[i++ % set.size()]);
    benchmark::DoNotOptimize(e.T_cam_target);
    iterations += e.iterations;
    converged += e.converged;
    ++solves;
  }
  state.counters["iterations"] = iterations / solves;
  state.counters["converged"] = converged / solves;
}

const int kRegistered = [] {
  for (const auto& name : vision::solver_names()) {
    benchmark::RegisterBenchmark(("solve/4pt/" + name).c_str(), BM_Solve, name, false)
        ->Unit(benchmark::kMicrosecond);
    if (name != "analytic" && name != "opencv_ippe_square")
      benchmark::RegisterBenchmark(("solve/16pt/" + name).c_str(), BM_Solve, name, true)
          ->Unit(benchmark::kMicrosecond);
  }
  return 0;
}();

}  // namespace

BENCHMARK_MAIN();
