// The fast solvers give the same poses as their straightforward first
// implementations, kept here as references: the analytic solver's closed-form
// nearest rotation against the SVD (nearest_rotation) it replaced. Seeded
// problems (0.5 px noise, 0.1-1.0 m, tilt up to 60 degrees), so the outcome is
// fixed.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <random>

#include "synthetic_pose.hpp"
#include "vision/correspondences.hpp"
#include "vision/pose_analytic.hpp"

namespace {

// The analytic square pose as first written (Maidi et al. 2010, eqs. 3-5;
// DOI 10.1007/s00138-008-0170-y), rotation made orthonormal by the SVD.
vision::Pose reference_analytic(const vision::Correspondences& c) {
  Eigen::Vector3d ray[4];
  for (int i = 0; i < 4; ++i)
    ray[i] = c.normalized[i].homogeneous();
  Eigen::Matrix3d M;
  M.col(0) = ray[1];
  M.col(1) = -ray[2];
  M.col(2) = ray[3];
  const Eigen::Vector3d z = M.inverse() * ray[0];
  Eigen::Vector3d P[4] = {ray[0], z(0) * ray[1], z(1) * ray[2], z(2) * ray[3]};
  const double scale = *c.square_side_m / (0.5 * ((P[1] - P[0]).norm() + (P[3] - P[0]).norm()));
  for (auto& p : P)
    p *= scale;
  const Eigen::Vector3d ac = P[2] - P[0], db = P[1] - P[3];
  Eigen::Matrix3d R;
  R.col(0) = (ac + db).normalized();
  R.col(1) = (ac - db).normalized();
  R.col(2) = R.col(0).cross(R.col(1));
  const auto& o = c.object_points;
  vision::Pose T_target_square;
  T_target_square.R.col(0) = (o[1] - o[0]).normalized();
  T_target_square.R.col(1) = (o[3] - o[0]).normalized();
  T_target_square.R.col(2) = T_target_square.R.col(0).cross(T_target_square.R.col(1));
  T_target_square.t = (o[0] + o[1] + o[2] + o[3]) / 4.0;
  const vision::Pose T_cam_square{vision::nearest_rotation(R), (P[0] + P[1] + P[2] + P[3]) / 4.0};
  return T_cam_square * T_target_square.inverse();
}

std::vector<vision::Correspondences> seeded_problems(const vision::Camera& camera,
                                                     bool whole_target, int count) {
  rig_test::ProblemSpec spec;
  spec.noise_px = 0.5;
  spec.whole_target = whole_target;
  std::mt19937_64 rng(23);
  std::vector<vision::Correspondences> out;
  for (int i = 0; i < count; ++i) {
    const auto p = rig_test::draw_problem(camera, spec, rng);
    out.push_back(vision::make_correspondences(camera, p.object_points, p.image_points_px));
  }
  return out;
}

// Both are the exact nearest rotation of the same matrix, computed two ways;
// rounding differs by a few ulps of entries of size <= 1 and of translations
// <= 1 m, so 1e-12 is thousands of ulps of margin.
TEST(AnalyticReference, ClosedFormRotationMatchesTheSvd) {
  const vision::Camera camera = vision::Camera::paper_default();
  int solved = 0;
  for (const auto& c : seeded_problems(camera, false, 2000)) {
    vision::Pose fast;
    std::string why;
    if (!vision::analytic_square_pose(c, &fast, &why)) continue;
    ++solved;
    const vision::Pose ref = reference_analytic(c);
    EXPECT_LE((fast.R - ref.R).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LE((fast.t - ref.t).cwiseAbs().maxCoeff(), 1e-12);
  }
  EXPECT_GE(solved, 1990);
}

}  // namespace
