// Every solver on noise-free problems over the paper's range: the pose is
// recovered to 1e-6 m and 1e-6 rad wherever the solver says it converged.
//
// Why 1e-6: with exact corners every solver's fixed point is the true pose;
// what remains is rounding and stopping rules. Doubles carry ~1e-16 relative,
// the Newton undistortion stops at 1e-9 px (~1e-12 rad of ray direction), and
// the iterative solvers stop at relative tolerances of 1e-12 or better, so
// errors are expected at 1e-9 or below; 1e-6 leaves margin without hiding a
// wrong minimum (the other planar solution differs by degrees).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "synthetic_pose.hpp"
#include "vision/correspondences.hpp"
#include "vision/pose_ekf.hpp"
#include "vision/solvers.hpp"

namespace {

constexpr double kTolerance = 1e-6;  // metres and radians
constexpr int kProblems = 300;

struct Tally {
  int total = 0, unconverged = 0, not_applicable = 0;
  double max_unconverged_tilt_rad = 0;
};

std::map<std::string, Tally> run_noise_free(bool whole_target) {
  const vision::Camera camera = vision::Camera::paper_default();
  rig_test::ProblemSpec spec;
  spec.whole_target = whole_target;
  std::mt19937_64 rng(whole_target ? 2 : 1);
  auto solvers = vision::make_all_solvers();
  // The EKF is told the data's noise (none): its measurement sigma is what
  // weighs the image against its fixed nominal prior, and what its
  // consistency gate is measured in. 1e-6 px keeps the prior's pull below 1e-9.
  vision::EkfOptions exact;
  exact.measurement_sigma_px = 1e-6;
  for (auto& s : solvers)
    if (s->name() == "ekf")
      s = std::make_unique<vision::EkfSolver>(exact);
    else if (s->name() == "hybrid_ekf")
      s = std::make_unique<vision::HybridEkfSolver>(exact);

  std::map<std::string, Tally> tally;
  for (int k = 0; k < kProblems; ++k) {
    const auto p = rig_test::draw_problem(camera, spec, rng);
    const auto c = vision::make_correspondences(camera, p.object_points, p.image_points_px);
    for (const auto& solver : solvers) {
      const vision::Estimate e = solver->solve(c);
      Tally& t = tally[solver->name()];
      ++t.total;
      if (!e.applicable()) {
        ++t.not_applicable;
        continue;
      }
      if (!e.converged) {
        ++t.unconverged;
        t.max_unconverged_tilt_rad = std::max(t.max_unconverged_tilt_rad, p.tilt_rad);
        continue;
      }
      const double dt = (e.T_cam_target.t - p.T_cam_target.t).norm();
      const double dR = vision::rotation_angle_between(e.T_cam_target.R, p.T_cam_target.R);
      EXPECT_LT(dt, kTolerance) << solver->name() << " problem " << k << " tilt " << p.tilt_rad;
      EXPECT_LT(dR, kTolerance) << solver->name() << " problem " << k << " tilt " << p.tilt_rad;
      EXPECT_NEAR(e.distance_m, p.T_cam_target.t.norm(), kTolerance) << solver->name();
      // 1e-6 rad of pose error moves a corner by at most f * 1e-6 = 7e-4 px.
      EXPECT_LT(e.reprojection_error_px, 1e-3) << solver->name();
    }
  }
  return tally;
}

// The failures to converge that are allowed, and why.
void expect_convergence(const std::string& name, const Tally& t) {
  if (name == "ekf") {
    // The plain EKF starts from a fixed nominal prior (frontal at 0.5 m), as
    // in the paper; far from it (in-plane turns beyond ~90 degrees, strong
    // tilt) it settles in a wrong minimum, which its consistency gate reports
    // as converged = false. That is the paper's finding (§3.1: "the algorithm
    // did not converge ... due to bad parameters initialization"). Measured:
    // it converges on ~40 % of these uniformly drawn poses; a quarter is the bar.
    EXPECT_GE(t.total - t.unconverged, t.total / 4);
  } else {
    EXPECT_EQ(t.unconverged, 0);
  }
}

TEST(PoseSolversNoiseFree, EverySolverRecoversTheMarkerPoseWhereItConverges) {
  const auto tally = run_noise_free(false);
  for (const auto& [name, t] : tally) {
    SCOPED_TRACE(name);
    EXPECT_EQ(t.not_applicable, 0);
    expect_convergence(name, t);
  }
}

TEST(PoseSolversNoiseFree, EverySolverButAnalyticRecoversTheWholeTargetPose) {
  const auto tally = run_noise_free(true);
  for (const auto& [name, t] : tally) {
    SCOPED_TRACE(name);
    if (name == "analytic" || name == "opencv_ippe_square") {
      EXPECT_EQ(t.not_applicable, t.total) << "square-only solvers must decline 16 points";
      continue;
    }
    EXPECT_EQ(t.not_applicable, 0);
    expect_convergence(name, t);
  }
}

}  // namespace
