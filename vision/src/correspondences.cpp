#include "vision/correspondences.hpp"

#include <Eigen/SVD>
#include <cmath>
#include <limits>
#include <sstream>

namespace vision {
namespace {

std::string fmt_point(const Eigen::Vector2d& p) {
  std::ostringstream s;
  s << "(" << p.x() << ", " << p.y() << ")";
  return s.str();
}

// Side of the square A, B, C, D (in that order around it) when the first four
// object points are one, relative tolerance 1e-9; nullopt otherwise.
std::optional<double> leading_square_side(const std::vector<Eigen::Vector3d>& p) {
  if (p.size() < 4) return std::nullopt;
  const Eigen::Vector3d ab = p[1] - p[0], ad = p[3] - p[0], dc = p[2] - p[3];
  const double side = ab.norm();
  if (!(side > 0)) return std::nullopt;
  const double tol = 1e-9 * side;
  const bool parallelogram = (ab - dc).norm() <= tol;
  const bool equal_sides = std::abs(ad.norm() - side) <= tol;
  const bool right_angle = std::abs(ab.dot(ad)) <= tol * side;
  if (parallelogram && equal_sides && right_angle) return side;
  return std::nullopt;
}

}  // namespace

Correspondences make_correspondences(const Camera& camera,
                                     const std::vector<Eigen::Vector3d>& object_points,
                                     const std::vector<Eigen::Vector2d>& image_points_px) {
  const size_t n = object_points.size();
  if (n != image_points_px.size())
    throw InputError("correspondences: " + std::to_string(n) + " object points but " +
                     std::to_string(image_points_px.size()) +
                     " image points (expected equal counts)");
  if (n < 4)
    throw InputError("correspondences: " + std::to_string(n) +
                     " points (expected at least 4 coplanar points)");
  for (size_t i = 0; i < n; ++i) {
    if (!object_points[i].allFinite())
      throw InputError("object point " + std::to_string(i) + " is not finite (NaN or infinity)");
    if (!image_points_px[i].allFinite())
      throw InputError("image point " + std::to_string(i) + " is not finite (NaN or infinity)");
  }

  Correspondences c;
  c.camera = &camera;
  c.object_points = object_points;
  c.image_points_px = image_points_px;

  // Extent, duplicates and the plane, from the SVD of the centred points.
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : object_points)
    centroid += p;
  centroid /= static_cast<double>(n);
  Eigen::MatrixXd centred(n, 3);
  double extent = 0;
  for (size_t i = 0; i < n; ++i) {
    centred.row(i) = (object_points[i] - centroid).transpose();
    extent = std::max(extent, centred.row(i).norm());
  }
  if (!(extent > 0)) throw InputError("object points: all points coincide (zero-size target)");
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) {
      if ((object_points[i] - object_points[j]).norm() <= 1e-9 * extent)
        throw InputError("object points " + std::to_string(i) + " and " + std::to_string(j) +
                         " coincide (expected distinct points)");
      if ((image_points_px[i] - image_points_px[j]).norm() <= 1e-9)
        throw InputError("image points " + std::to_string(i) + " and " + std::to_string(j) +
                         " coincide at " + fmt_point(image_points_px[i]) +
                         " px (expected distinct points)");
    }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(centred, Eigen::ComputeThinV);
  const Eigen::Vector3d sv = svd.singularValues();
  if (sv(1) <= 1e-6 * sv(0))
    throw InputError("object points are collinear (expected points spanning a plane)");
  if (sv(2) > 1e-6 * sv(0))
    throw InputError("object points are not coplanar (out-of-plane spread " +
                     std::to_string(sv(2) / sv(0)) + " of the in-plane extent; expected < 1e-6)");

  bool on_z0 = true;
  for (const auto& p : object_points)
    on_z0 = on_z0 && std::abs(p.z()) <= 1e-12 * extent;
  if (!on_z0) {
    Eigen::Matrix3d R = svd.matrixV();
    if (R.determinant() < 0) R.col(2) *= -1;
    c.T_target_plane = Pose{R, centroid};
  }
  const Pose T_plane_target = c.T_target_plane.inverse();
  c.plane_points.reserve(n);
  for (const auto& p : object_points)
    c.plane_points.push_back((T_plane_target * p).head<2>());

  c.normalized = camera.undistort_points(image_points_px);
  for (size_t i = 0; i < n; ++i)
    if (!c.normalized[i].allFinite())
      throw InputError("image point " + std::to_string(i) + " " + fmt_point(image_points_px[i]) +
                       " px cannot be undistorted: it lies outside the region where the lens "
                       "model is invertible (expected a pixel near the image)");
  c.square_side_m = leading_square_side(object_points);
  return c;
}

double reprojection_rms_px(const Correspondences& c, const Pose& T_cam_target) {
  double sum = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector3d p = T_cam_target * c.object_points[i];
    if (!(p.z() > 0)) return std::numeric_limits<double>::infinity();
    sum += (c.camera->project(p) - c.image_points_px[i]).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(c.size()));
}

bool in_front_of_camera(const Correspondences& c, const Pose& T_cam_target) {
  for (const auto& p : c.object_points)
    if (!((T_cam_target * p).z() > 0)) return false;
  return true;
}

}  // namespace vision
