// Convergence of the OI solvers (Lu, Hager & Mjolsness, "Fast and globally
// convergent pose estimation from video images", IEEE PAMI 22(6), 2000; the
// hybrid: Maidi et al. 2010, §2.2, doi:10.1007/s00138-008-0170-y) on problems
// that no other test draws, from fixed seeds (the outcome is fixed):
//  - oi on 300 noise-free marker poses and 300 whole-sheet poses of seeds the
//    noise-free test does not use: every one converges. Near frontal the two
//    planar minima merge and OI's linear rate tends to 1 (it crawls); the
//    SQUAREM extrapolation and the Newton finish must still end every run;
//  - hybrid_oi on bench_solvers' own 4-point problems (seed 7, 0.5 px noise,
//    the 256 poses whose solve time it reports): converged on all of them;
//  - oi and hybrid_oi on corners detected in simulated sweep frames near
//    frontal, where OI reaches its cap and the Newton finish ends at rounding.
// Where they converge, the pose must be the truth (noise-free) or explain the
// corners as well as the noise allows (noisy): see the bars below.
#include <gtest/gtest.h>

#include <cmath>

#include "synthetic_pose.hpp"
#include "vision/correspondences.hpp"
#include "vision/solvers.hpp"

namespace {

TEST(OiConvergence, ConvergesOnHeldOutNoiseFreePoses) {
  const vision::Camera camera = vision::Camera::paper_default();
  const auto solver = vision::make_solver("oi");
  for (bool whole_target : {false, true}) {
    rig_test::ProblemSpec spec;
    spec.whole_target = whole_target;
    std::mt19937_64 rng(whole_target ? 1002 : 1001);
    int unconverged = 0;
    for (int k = 0; k < 300; ++k) {
      const auto p = rig_test::draw_problem(camera, spec, rng);
      const auto c = vision::make_correspondences(camera, p.object_points, p.image_points_px);
      const vision::Estimate e = solver->solve(c);
      if (!e.converged) {
        ++unconverged;
        ADD_FAILURE() << "problem " << k << " tilt " << p.tilt_rad << ": " << e.message;
        continue;
      }
      // Noise-free: the fixed point is the true pose, to rounding and the
      // stopping rule (pose_noise_free_test.cpp derives the 1e-6).
      EXPECT_LT((e.T_cam_target.t - p.T_cam_target.t).norm(), 1e-6) << "problem " << k;
    }
    EXPECT_EQ(unconverged, 0) << (whole_target ? "16 points" : "4 points");
  }
}

TEST(OiConvergence, HybridOiConvergesOnEveryBenchmarkPose) {
  const vision::Camera camera = vision::Camera::paper_default();
  const auto solver = vision::make_solver("hybrid_oi");
  rig_test::ProblemSpec spec;  // bench_solvers' problems: seed 7, 0.5 px noise, 4 points
  spec.noise_px = 0.5;
  std::mt19937_64 rng(7);
  int unconverged = 0;
  for (int k = 0; k < 256; ++k) {
    const auto p = rig_test::draw_problem(camera, spec, rng);
    const auto c = vision::make_correspondences(camera, p.object_points, p.image_points_px);
    const vision::Estimate e = solver->solve(c);
    unconverged += !e.converged;
    EXPECT_TRUE(e.converged) << "problem " << k << ": " << e.message;
    // 0.5 px per coordinate of noise on 8 coordinates, 6 pose parameters
    // fitted: the residual's sum of squares / sigma^2 is chi-square with 2
    // degrees of freedom, RMS 0.5 sqrt(2/8) = 0.25 px in expectation. An RMS
    // of 2 px is a chi-square of 128, probability e^-64: a wrong minimum.
    EXPECT_LT(e.reprojection_error_px, 2.0) << "problem " << k;
  }
  EXPECT_EQ(unconverged, 0);
}

// The pose marker's corners as two detectors found them in frames of a
// simulated sweep (config/sweeps/ci.toml, the `lab` realism profile): the
// 5 cm marker 0.96 m and 0.78 m away, about 2 degrees from frontal. There the
// two planar minima of OI's object-space error E have nearly merged: E's
// smallest curvature is ~1e-4 of its largest, OI crawls to its 500-step cap,
// and Newton's steps stop moving E by more than its rounding (~1e-19 of its
// ~1e-9) while still ~1e-7 rad from the exact minimum along the flat
// direction. Both solvers must call that converged, and, both minimising the
// same E, agree: the flat direction is resolved to sqrt(2 x 1e-19 / 1.4e-6)
// = 4e-7 rad, which moves a pose 1 m away by 0.4 um, so two runs that each
// stop within that of the minimum are within 0.8 um of each other.
TEST(OiConvergence, ConvergesNearFrontalOnSweepCorners) {
  const vision::Camera camera = vision::Camera::paper_default();
  const double h = 0.025;  // half the marker's side, m
  const std::vector<Eigen::Vector3d> square = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};
  const std::vector<std::vector<Eigen::Vector2d>> corners = {
      {{380.438413717779, 254.624131228012},  // rig's detector, 0.96 m
       {417.176624925352, 254.270642721611},
       {417.468021530315, 292.351491158047},
       {380.751801581458, 292.683406982223}},
      {{359.635131835937, 250.298721313477},  // cv::aruco, subpixel corners, 0.78 m
       {405.037139892578, 249.804412841797},
       {405.41552734375, 296.847930908203},
       {360.027923583984, 297.354400634766}}};
  for (const auto& px : corners) {
    const auto c = vision::make_correspondences(camera, square, px);
    const vision::Estimate oi = vision::make_solver("oi")->solve(c);
    const vision::Estimate hybrid = vision::make_solver("hybrid_oi")->solve(c);
    EXPECT_TRUE(oi.converged) << oi.message;
    EXPECT_TRUE(hybrid.converged) << hybrid.message;
    EXPECT_LT((oi.T_cam_target.t - hybrid.T_cam_target.t).norm(), 0.8e-6);
  }
}

}  // namespace
