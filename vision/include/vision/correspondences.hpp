// vision::Correspondences: 2D-3D point pairs prepared once for every solver.
//
// The input is what a detector or a user gives: object points in the target
// frame (metres) and the pixels where the camera saw them (distorted, OpenCV
// pixel convention). make_correspondences validates them, undistorts the
// pixels once through the camera model (solvers work on undistorted normalized
// points, never on distortion) and finds the plane the object points lie on.
#pragma once

#include <optional>
#include <stdexcept>
#include <vector>

#include "vision/camera.hpp"
#include "vision/pose.hpp"

namespace vision {

// Correspondences that no solver can use: too few points, counts that differ,
// NaN, duplicated or collinear object points, non-coplanar object points,
// pixels outside the invertible region of the lens model. The message names
// the point and what was expected.
class InputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct Correspondences {
  const Camera* camera = nullptr;                // the model the pixels came through; not owned
  std::vector<Eigen::Vector3d> object_points;    // target frame, metres
  std::vector<Eigen::Vector2d> image_points_px;  // observed, distorted pixels
  std::vector<Eigen::Vector2d> normalized;       // undistorted, (X/Z, Y/Z) of the camera frame

  // The object plane: plane_points[i] = (x, y) with
  // object_points[i] = T_target_plane * (x, y, 0). Identity when the points
  // already lie on z = 0 of the target frame.
  Pose T_target_plane;
  std::vector<Eigen::Vector2d> plane_points;  // metres

  // When the first four object points are the corners of a square in the order
  // A, B, C, D around it (the pose marker), its side in metres; the analytic
  // solver needs that, the hybrids start from it.
  std::optional<double> square_side_m;

  size_t size() const { return object_points.size(); }
};

// Validates and prepares correspondences. Preconditions are checked and
// reported as InputError: at least 4 points, equal counts, finite values,
// object points pairwise distinct (relative 1e-9 of their extent), not all on
// one line, all on one plane (out-of-plane spread below 1e-6 of the extent),
// and every pixel invertible through the lens model.
Correspondences make_correspondences(const Camera& camera,
                                     const std::vector<Eigen::Vector3d>& object_points,
                                     const std::vector<Eigen::Vector2d>& image_points_px);

// Root-mean-square distance, in pixels, between the observed pixels and the
// object points projected through T_cam_target and the full camera model
// (with distortion). Infinite when a point falls on or behind the camera.
double reprojection_rms_px(const Correspondences& c, const Pose& T_cam_target);

// True when every object point lies in front of the camera (z > 0).
bool in_front_of_camera(const Correspondences& c, const Pose& T_cam_target);

}  // namespace vision
