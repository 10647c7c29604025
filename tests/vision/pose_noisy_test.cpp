// Every solver on noisy problems (0.5 px Gaussian corner noise, 1,000 poses of
// the paper's 5 cm marker at 0.10-1.00 m, tilt up to 60 degrees, the paper's
// camera with distortion), compared with opencv_ippe_square on the same
// problems. The statistics of the comparison are paired: each problem is
// solved by every solver, and a difference of means is judged against the
// standard error of the per-problem differences, at kStandardErrors.
//
// The problems come from a fixed seed, so every run sees the same numbers
// (measured: |z| <= 1.7 between solvers of equal accuracy, >= 22 for the
// poor ones). 5.5 standard errors would be passed by chance, under
// normality, with probability 1.9e-8 one-sided and 3.8e-8 two-sided: below
// 1e-6 over the ten comparisons with any other seed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "synthetic_pose.hpp"
#include "vision/correspondences.hpp"
#include "vision/solvers.hpp"

namespace {

constexpr int kNoisyProblems = 1000;
constexpr double kNoisePx = 0.5;
constexpr double kStandardErrors = 5.5;

struct Results {
  std::vector<std::string> names;
  // error[solver][problem]: |distance estimate - true distance| / true distance;
  // NaN where the solver did not converge.
  std::map<std::string, std::vector<double>> error;
};

const Results& results() {
  static const Results r = [] {
    Results out;
    const vision::Camera camera = vision::Camera::paper_default();
    rig_test::ProblemSpec spec;
    spec.noise_px = kNoisePx;
    std::mt19937_64 rng(42);
    auto solvers = vision::make_all_solvers();
    for (const auto& s : solvers)
      out.names.push_back(s->name());
    for (int k = 0; k < kNoisyProblems; ++k) {
      const auto p = rig_test::draw_problem(camera, spec, rng);
      const auto c = vision::make_correspondences(camera, p.object_points, p.image_points_px);
      const double truth = p.T_cam_target.t.norm();
      for (const auto& s : solvers) {
        const auto e = s->solve(c);
        out.error[s->name()].push_back(e.converged ? std::abs(e.distance_m - truth) / truth
                                                   : std::nan(""));
      }
    }
    return out;
  }();
  return r;
}

struct Paired {
  double mean_difference = 0, standard_error = 0;
  int n = 0;
};

// Mean and standard error of a[i] - b[i] over problems where both converged.
Paired paired(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> d;
  for (size_t i = 0; i < a.size(); ++i)
    if (std::isfinite(a[i]) && std::isfinite(b[i])) d.push_back(a[i] - b[i]);
  Paired p;
  p.n = static_cast<int>(d.size());
  for (double x : d)
    p.mean_difference += x;
  p.mean_difference /= p.n;
  double ss = 0;
  for (double x : d)
    ss += (x - p.mean_difference) * (x - p.mean_difference);
  p.standard_error = std::sqrt(ss / (p.n - 1) / p.n);
  return p;
}

double mean_of_finite(const std::vector<double>& v, int* n) {
  double s = 0;
  *n = 0;
  for (double x : v)
    if (std::isfinite(x)) s += x, ++*n;
  return s / *n;
}

double percentile_95(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(0.95 * (v.size() - 1))];
}

TEST(PoseSolversNoisy, TableAgainstOpenCvIppeSquare) {
  const auto& r = results();
  const auto& reference = r.error.at("opencv_ippe_square");
  std::printf("%-20s %9s %10s %10s %14s\n", "solver", "converged", "mean_err%", "p95_err%",
              "vs_ref_mean%");
  for (const auto& name : r.names) {
    int n = 0;
    const double mean = mean_of_finite(r.error.at(name), &n);
    const Paired d = paired(r.error.at(name), reference);
    std::printf("%-20s %9d %10.4f %10.4f %+8.4f+-%.4f\n", name.c_str(), n, 100 * mean,
                100 * percentile_95(r.error.at(name)), 100 * d.mean_difference,
                100 * d.standard_error);
    if (name != "ekf") {
      // Every solver but the fixed-prior EKF converges on nearly every
      // problem; the 1 % allowance covers OI's near-frontal crawl.
      EXPECT_GE(n, kNoisyProblems * 99 / 100) << name;
    }
  }
}

TEST(PoseSolversNoisy, IppeMatchesOpenCvIppeSquare) {
  // The same algorithm (Collins & Bartoli), written twice: no difference in
  // mean error beyond the sample's statistical noise.
  const auto& r = results();
  const Paired d = paired(r.error.at("ippe"), r.error.at("opencv_ippe_square"));
  EXPECT_LT(std::abs(d.mean_difference), kStandardErrors * d.standard_error + 1e-12);
}

TEST(PoseSolversNoisy, LmIsNotWorseThanAnyOtherSolver) {
  // lm is the maximum-likelihood estimate under this noise model; no solver
  // may beat it by more than kStandardErrors of the paired difference.
  const auto& r = results();
  for (const auto& name : r.names) {
    if (name == "lm") continue;
    const Paired d = paired(r.error.at("lm"), r.error.at(name));
    EXPECT_LT(d.mean_difference, kStandardErrors * d.standard_error) << "lm vs " << name;
  }
}

}  // namespace
