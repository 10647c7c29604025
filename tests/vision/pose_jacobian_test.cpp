// vision::project_with_jacobian against central differences of the camera model
// itself, at 0.15-1 m and across the image (where the lens distortion is
// strongest), in the parameterisation the header states.
#include "vision/pose_jacobian.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "synthetic_pose.hpp"

namespace {

// The pose perturbed by the increments (w, v) of vision/pose_jacobian.hpp.
vision::Pose perturbed(const vision::Pose& T, int parameter, double step) {
  vision::Pose out = T;
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  axis(parameter % 3) = 1;
  if (parameter < 3)
    out.R = Eigen::AngleAxisd(step, axis).toRotationMatrix() * T.R;
  else
    out.t += step * axis;
  return out;
}

TEST(ProjectionJacobian, MatchesCentralDifferencesOfTheCameraModel) {
  // Central differences with h = 1e-6 (rad, m) err by rounding, ~2e-16 *
  // 736 px / h = 1.6e-7 px per unit, plus truncation, h^2 / 6 * |f'''| with
  // |f'''| <= 6 fx |X| / Z^4 ~ 8.5e5 px/m^3 at Z = 0.15 m: 1.4e-7. 1e-5 px
  // per unit is ten times their sum (the largest error seen here is 1.2e-7),
  // and far below any formula error: the entries are 1e2 to 5e3 px per unit,
  // and leaving out the distortion alone changes them by percents.
  constexpr double kStep = 1e-6;
  constexpr double kTolerance = 1e-5;
  const vision::Camera camera = vision::Camera::paper_default();
  rig_test::ProblemSpec spec;
  spec.min_distance_m = 0.15;
  spec.whole_target = true;
  std::mt19937_64 rng(11);
  int compared = 0;
  for (int i = 0; i < 50; ++i) {
    const rig_test::Problem problem = rig_test::draw_problem(camera, spec, rng);
    const vision::Pose& T = problem.T_cam_target;
    for (const Eigen::Vector3d& P : problem.object_points) {
      Eigen::Vector2d pixel;
      vision::ProjectionJacobian J;
      ASSERT_TRUE(vision::project_with_jacobian(camera, T, P, &pixel, &J));
      // The camera model's own pixel (the same arithmetic: rounding at most).
      EXPECT_LT((pixel - camera.project(T * P)).norm(), 1e-9);
      for (int k = 0; k < 6; ++k) {
        const Eigen::Vector2d numeric = (camera.project(perturbed(T, k, kStep) * P) -
                                         camera.project(perturbed(T, k, -kStep) * P)) /
                                        (2 * kStep);
        EXPECT_NEAR(J(0, k), numeric.x(), kTolerance) << "problem " << i << ", parameter " << k;
        EXPECT_NEAR(J(1, k), numeric.y(), kTolerance) << "problem " << i << ", parameter " << k;
        ++compared;
      }
    }
  }
  EXPECT_EQ(compared, 50 * 16 * 6);
}

TEST(ProjectionJacobian, IsThePinholeJacobianWithoutDistortion) {
  // No distortion, p = (X, Y, Z) = R P + t: d(u, v)/dv = [fx/Z 0 -fx X/Z^2;
  // 0 fy/Z -fy Y/Z^2]. w_z turns R P = (a, b, 0) about the target origin t,
  // moving p by w_z (-b, a, 0): d u / d w_z = -fx b / Z, d v / d w_z = fy a / Z.
  const vision::Camera pinhole({700, 720, 368, 285}, {}, 736, 571);
  const vision::Pose T{Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.02, -0.03, 0.5)};
  const Eigen::Vector3d P(0.05, 0.04, 0);
  const double a = 0.05, b = 0.04, X = 0.07, Y = 0.01, Z = 0.5;
  Eigen::Vector2d pixel;
  vision::ProjectionJacobian J;
  ASSERT_TRUE(vision::project_with_jacobian(pinhole, T, P, &pixel, &J));
  // Rounding only: a few ulps of entries below 1e4.
  constexpr double kRounding = 1e-9;
  EXPECT_NEAR(J(0, 3), 700 / Z, kRounding);
  EXPECT_NEAR(J(0, 4), 0, kRounding);
  EXPECT_NEAR(J(0, 5), -700 * X / (Z * Z), kRounding);
  EXPECT_NEAR(J(1, 3), 0, kRounding);
  EXPECT_NEAR(J(1, 4), 720 / Z, kRounding);
  EXPECT_NEAR(J(1, 5), -720 * Y / (Z * Z), kRounding);
  EXPECT_NEAR(J(0, 2), -700 * b / Z, kRounding);
  EXPECT_NEAR(J(1, 2), 720 * a / Z, kRounding);
}

TEST(ProjectionJacobian, RefusesAPointOnOrBehindTheCamera) {
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::Pose T{Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 0.5)};
  for (const double z : {-0.5, -0.6, std::nan("")}) {
    Eigen::Vector2d pixel(7, 7);
    vision::ProjectionJacobian J = vision::ProjectionJacobian::Constant(7);
    EXPECT_FALSE(vision::project_with_jacobian(camera, T, Eigen::Vector3d(0.01, 0, z), &pixel, &J))
        << "z " << z;
    EXPECT_EQ(pixel, Eigen::Vector2d(7, 7));
    EXPECT_EQ(J, vision::ProjectionJacobian::Constant(7));
  }
}

}  // namespace
