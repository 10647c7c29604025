// Internal: the plane-to-image homography used by IPPE.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace vision::detail {

// H with H(2,2) = 1 mapping plane points (metres) to undistorted normalized
// image points, x ~ H (X, Y, 1)^T. Least squares on the linearised (DLT)
// equations after Hartley normalisation of both point sets (Hartley &
// Zisserman 2004, Alg. 4.2); exact for four points. Returns false when the
// points give no unique homography (three or more collinear among four).
bool plane_homography(const std::vector<Eigen::Vector2d>& plane,
                      const std::vector<Eigen::Vector2d>& image, Eigen::Matrix3d* H);

}  // namespace vision::detail
