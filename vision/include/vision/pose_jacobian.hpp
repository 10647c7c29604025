// vision::project_with_jacobian: the pixel of one target point and how it
// moves when the pose T_cam_target is perturbed. The Jacobian of the
// reprojection error that refine_lm descends (vision/pose_lm.hpp) and the one
// the Cramér-Rao bound on a pose is built from (vision/cramer_rao.hpp).
//
// Parameterisation: six increments (w, v) applied in the camera frame,
//   R(w) = exp([w]x) R,   t(v) = t + v,
// w a rotation vector (radians, camera axes, left-multiplied onto R: it
// turns the target about its own origin), v a translation (metres, camera
// axes). The point P (target frame, metres) is then at
// p_cam = exp([w]x) R P + t + v and seen at camera.project(p_cam).
// At w = v = 0, with p = R P + t = (X, Y, Z) and (x, y) = (X/Z, Y/Z):
//   d pixel / d(w, v) = D [ -[R P]x | I ],
//   D = d pixel / d p = Camera::distort_jacobian(x, y) [1/Z 0 -x/Z; 0 1/Z -y/Z],
// [a]x being the cross-product matrix of a ([a]x b = a x b).
#pragma once

#include <Eigen/Core>

#include "vision/camera.hpp"
#include "vision/pose.hpp"

namespace vision {

// Row 0: d u, row 1: d v (distorted pixels of `camera`); columns w_x, w_y,
// w_z (px per radian), then v_x, v_y, v_z (px per metre).
using ProjectionJacobian = Eigen::Matrix<double, 2, 6>;

// The pixel camera.project(T_cam_target * P_target) into *pixel and, when
// `jacobian` is not null, its derivative in (w, v) at the pose itself. Returns
// false, writing nothing, when the point is on or behind the camera (z <= 0,
// or not a number). Does not throw.
// Always inlined: it runs once per point and iteration of refine_lm, where a
// call and the Jacobian's round trip through memory cost 5 % of the solve.
[[gnu::always_inline]] inline bool project_with_jacobian(const Camera& camera,
                                                         const Pose& T_cam_target,
                                                         const Eigen::Vector3d& P_target,
                                                         Eigen::Vector2d* pixel,
                                                         ProjectionJacobian* jacobian) {
  const Eigen::Vector3d RP = T_cam_target.R * P_target;
  const Eigen::Vector3d p = RP + T_cam_target.t;
  if (!(p.z() > 0)) return false;
  const Eigen::Vector2d xy = p.head<2>() / p.z();
  *pixel = camera.distort_normalized(xy);
  if (!jacobian) return true;
  // d(px)/d(p) = d(px)/d(xy) * d(xy)/d(p); d(p)/dw = -[RP]x; d(p)/dv = I.
  Eigen::Matrix<double, 2, 3> dxy_dp;
  dxy_dp << 1 / p.z(), 0, -xy.x() / p.z(), 0, 1 / p.z(), -xy.y() / p.z();
  const Eigen::Matrix<double, 2, 3> dpx_dp = camera.distort_jacobian(xy) * dxy_dp;
  Eigen::Matrix3d skew;
  skew << 0, -RP.z(), RP.y(), RP.z(), 0, -RP.x(), -RP.y(), RP.x(), 0;
  jacobian->leftCols<3>() = -dpx_dp * skew;
  jacobian->rightCols<3>() = dpx_dp;
  return true;
}

}  // namespace vision
