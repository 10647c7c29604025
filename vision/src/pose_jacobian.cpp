#include "vision/pose_jacobian.hpp"

namespace vision {

ProjectionJacobian projection_jacobian(const Camera& camera, const Pose& T_cam_target,
                                       const Eigen::Vector3d& P_target) {
  const Eigen::Vector3d RP = T_cam_target.R * P_target;
  const Eigen::Vector3d p = RP + T_cam_target.t;
  const Eigen::Vector2d xy = p.head<2>() / p.z();
  // d(px)/d(p) = d(px)/d(xy) * d(xy)/d(p); d(p)/dw = -[RP]x; d(p)/dv = I.
  Eigen::Matrix<double, 2, 3> dxy_dp;
  dxy_dp << 1 / p.z(), 0, -xy.x() / p.z(), 0, 1 / p.z(), -xy.y() / p.z();
  const Eigen::Matrix<double, 2, 3> dpx_dp = camera.distort_jacobian(xy) * dxy_dp;
  Eigen::Matrix3d skew;
  skew << 0, -RP.z(), RP.y(), RP.z(), 0, -RP.x(), -RP.y(), RP.x(), 0;
  ProjectionJacobian J;
  J.leftCols<3>() = -dpx_dp * skew;
  J.rightCols<3>() = dpx_dp;
  return J;
}

}  // namespace vision
