// Synthetic pose problems over the paper's working range, for tests and
// benchmarks: a square marker (the paper's 5 cm) or a whole target sheet seen
// by the paper's camera at 0.10-1.00 m, tilted up to a limit, at any in-plane
// rotation, anywhere in the image, with optional Gaussian corner noise.
#pragma once

#include <random>
#include <vector>

#include "vision/camera.hpp"
#include "vision/pose.hpp"

namespace rig_test {

struct ProblemSpec {
  double min_distance_m = 0.10;  // camera centre to marker centre
  double max_distance_m = 1.00;
  double max_tilt_rad = 60.0 * M_PI / 180.0;  // angle between sheet normal and line of sight
  double side_m = 0.05;                       // the paper's 5 cm marker
  double noise_px = 0.0;                      // sigma of Gaussian corner noise, per axis
  double margin_px = 2.0;                     // keep every corner this far inside the image
  bool whole_target = false;  // 16 corners: a 2x2 sheet of markers (pose marker first)
};

struct Problem {
  vision::Pose T_cam_target;                     // ground truth
  std::vector<Eigen::Vector3d> object_points;    // target frame, metres
  std::vector<Eigen::Vector2d> image_points_px;  // distorted, with noise
  double tilt_rad = 0;
};

// Corners A, B, C, D (x right, y down, z into the sheet) of a square of side s
// centred at (cx, cy) in the target frame.
std::vector<Eigen::Vector3d> square_corners(double side_m, double cx = 0, double cy = 0);

// Draws one problem whose every corner projects inside the image. The marker
// centre is at a uniformly drawn distance along a ray through a uniformly drawn
// pixel; the sheet is tilted by a uniformly drawn angle about a random in-plane
// axis and rotated in its plane by a uniform angle.
Problem draw_problem(const vision::Camera& camera, const ProblemSpec& spec, std::mt19937_64& rng);

}  // namespace rig_test
