#include "square_frame.hpp"

namespace vision::detail {

Pose square_in_target(const Correspondences& c) {
  const auto& p = c.object_points;
  const Eigen::Vector3d x = (p[1] - p[0]).normalized();
  const Eigen::Vector3d y = (p[3] - p[0]).normalized();
  Pose T;
  T.R.col(0) = x;
  T.R.col(1) = y;
  T.R.col(2) = x.cross(y);
  T.t = (p[0] + p[1] + p[2] + p[3]) / 4.0;
  return T;
}

}  // namespace vision::detail
