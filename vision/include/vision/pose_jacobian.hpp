// vision::projection_jacobian: how the pixel of one target point moves when
// the pose T_cam_target is perturbed. The Jacobian of the reprojection error
// that refine_lm descends (vision/pose_lm.hpp) and the one the Cramér-Rao
// bound on a pose is built from (vision/cramer_rao.hpp).
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

// d camera.project(T_cam_target * P_target) / d(w, v) at the pose itself.
// Precondition: the point is in front of the camera, (T_cam_target *
// P_target).z() > 0; callers check that first (on or behind the camera the
// entries are meaningless, and not finite at z = 0). Does not throw.
ProjectionJacobian projection_jacobian(const Camera& camera, const Pose& T_cam_target,
                                       const Eigen::Vector3d& P_target);

}  // namespace vision
