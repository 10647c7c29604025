// rig::sweep::ground_truth_at: the physics a report compares solvers with. The
// Cramér-Rao bound is checked the way it is defined: the maximum-likelihood
// solver (lm) on corners with independent Gaussian noise has a distance
// spread equal to the bound, to within the sampling error of a spread.
#include "rig/sweep/ground_truth.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "vision/correspondences.hpp"
#include "vision/solvers.hpp"

namespace {

constexpr double kPi = 3.14159265358979323846;

vision::RigGeometry head_on(double target_tilt_about_y_deg) {
  return vision::RigGeometry::from_mount(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                         Eigen::Vector3d(1000, 150, 0),
                                         Eigen::Vector3d(0, target_tilt_about_y_deg, 0));
}

TEST(GroundTruth, DistanceAndViewingAngleFollowTheGeometry) {
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::Target target = vision::Target::paper_default();
  // Straight down the bench, 0.6 m from the target: head-on, then the sheet
  // turned 30 degrees about its vertical axis.
  const rig::sweep::GroundTruth square =
      rig::sweep::ground_truth_at(head_on(0), camera, target, 400, 150);
  EXPECT_NEAR(square.distance_m, 0.600, 1e-12);
  EXPECT_NEAR(square.viewing_angle_deg, 0.0, 1e-6);
  const rig::sweep::GroundTruth turned =
      rig::sweep::ground_truth_at(head_on(30), camera, target, 400, 150);
  EXPECT_NEAR(turned.viewing_angle_deg, 30.0, 1e-9);
  // Off to the side by 100 mm at 0.6 m: the line of sight leans atan(1/6).
  const rig::sweep::GroundTruth aside =
      rig::sweep::ground_truth_at(head_on(0), camera, target, 400, 50);
  EXPECT_NEAR(aside.viewing_angle_deg, std::atan(100.0 / 600.0) * 180 / kPi, 1e-9);
}

TEST(GroundTruth, MarkersInViewAndTheirSizeFollowTheDistance) {
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::Target target = vision::Target::paper_default();
  const rig::sweep::GroundTruth far =
      rig::sweep::ground_truth_at(head_on(0), camera, target, 0, 150);
  const rig::sweep::GroundTruth near =
      rig::sweep::ground_truth_at(head_on(0), camera, target, 900, 150);
  EXPECT_EQ(far.visible_markers.size(), target.markers.size());  // 1 m: the whole sheet
  ASSERT_EQ(near.visible_markers.size(), 1u);                    // 0.1 m: the pose marker
  EXPECT_EQ(near.visible_markers[0].marker_id, target.pose_marker_id);
  // A 50 mm marker at distance d spans about f * 0.05 / d px (f ~ 706-731 px;
  // the lens's barrel distortion shrinks it a little at the edge of view).
  EXPECT_NEAR(near.visible_markers[0].side_px, 718.6 * 0.05 / 0.1, 0.05 * 359.3);
  for (const auto& m : far.visible_markers)
    EXPECT_NEAR(m.side_px, 718.6 * 0.05 / 1.0, 0.05 * 35.9) << m.marker_id;
}

// lm is the maximum-likelihood estimator for independent Gaussian corner
// noise, asymptotically efficient: its distance spread over many noisy draws
// is sigma times the bound. 4,000 draws estimate a spread to 1/sqrt(2 * 4000)
// = 1.1 % (one standard error); at sigma = 0.2 px the estimator's second-order
// bias and excess spread are far smaller. 6 % is 5.4 standard errors. The
// noise comes from a fixed seed (measured: 1.0 % and 1.8 % above the bound);
// over seeds 1 to 8 the ratio spread by 1.0 % around 1.00, and another seed
// would fail with probability 7e-8.
void expect_lm_attains_the_bound(double x_mm, const std::string& scope) {
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::Target target = vision::Target::paper_default();
  const vision::RigGeometry geometry = head_on(20);
  const rig::sweep::GroundTruth truth =
      rig::sweep::ground_truth_at(geometry, camera, target, x_mm, 150);
  double bound = -1;
  for (const auto& b : truth.distance_bounds)
    if (b.scope == scope) bound = b.distance_sd_m_per_px;
  ASSERT_GT(bound, 0) << scope;

  std::vector<Eigen::Vector3d> object;
  std::vector<Eigen::Vector2d> image;
  for (const auto& m : truth.visible_markers) {
    if (scope != "target" && m.marker_id != target.pose_marker_id) continue;
    for (const auto& corner : target.corners_m(m.marker_id)) {
      object.push_back(corner);
      image.push_back(camera.project(truth.T_cam_target.R * corner + truth.T_cam_target.t));
    }
  }
  const auto lm = vision::make_solver("lm");
  const double sigma = 0.2;
  std::mt19937_64 random(7);
  std::normal_distribution<double> noise(0.0, sigma);
  const int draws = 4000;
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int i = 0; i < draws; ++i) {
    std::vector<Eigen::Vector2d> noisy = image;
    for (auto& p : noisy)
      p += Eigen::Vector2d(noise(random), noise(random));
    const vision::Estimate e = lm->solve(vision::make_correspondences(camera, object, noisy),
                                         vision::SolverHint{truth.T_cam_target, std::nullopt});
    if (!e.converged) continue;
    sum += e.distance_m;
    sum2 += e.distance_m * e.distance_m;
    ++n;
  }
  ASSERT_GT(n, draws * 99 / 100);
  const double mean = sum / n;
  const double sd = std::sqrt((sum2 - n * mean * mean) / (n - 1));
  EXPECT_NEAR(sd / (sigma * bound), 1.0, 0.06)
      << scope << " at x " << x_mm << " mm: sd " << sd << " m, bound " << sigma * bound << " m";
}

TEST(GroundTruth, TheMaximumLikelihoodSolverAttainsTheDistanceBoundOnThePoseMarker) {
  expect_lm_attains_the_bound(500, "0");
}

TEST(GroundTruth, TheMaximumLikelihoodSolverAttainsTheDistanceBoundOnTheWholeTarget) {
  expect_lm_attains_the_bound(300, "target");
}

}  // namespace
