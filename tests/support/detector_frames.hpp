// The frame set of the detector tests and benchmarks: the
// paper's camera looking at the paper's sheet of 5 cm markers, the pose marker
// at 0.10-1.00 m anywhere in the image, the sheet tilted up to 40 degrees from
// the line of sight, any in-plane rotation. Deterministic from a seed.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "vision/camera.hpp"
#include "vision/pose.hpp"

namespace detector_test {

constexpr double kPi = 3.14159265358979323846;

struct PoseRange {
  double min_distance_m = 0.10;
  double max_distance_m = 1.00;
  double max_tilt_deg = 40.0;
};

// A pose whose target-frame origin (the pose marker's centre) is at
// `distance_m` from the camera, seen along a random pixel ray kept far enough
// from the image border for a marker of `marker_side_m` to fit, with the sheet
// normal `tilt_deg` away from that ray about a random axis, and a random
// in-plane rotation.
inline vision::Pose sample_pose(const vision::Camera& camera, double distance_m, double tilt_deg,
                                double marker_side_m, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0, 1);
  const auto& k = camera.intrinsics();
  // Marker half-diagonal in pixels, grown for perspective at close range.
  const double half_px = 0.75 * marker_side_m * k.fx / distance_m + 12;
  const double w = camera.width_px(), h = camera.height_px();
  const double u = half_px < w / 2 ? half_px + unit(rng) * (w - 2 * half_px) : w / 2;
  const double v = half_px < h / 2 ? half_px + unit(rng) * (h - 2 * half_px) : h / 2;
  Eigen::Vector2d n;
  camera.undistort_point(Eigen::Vector2d(u, v), &n);
  const Eigen::Vector3d ray = Eigen::Vector3d(n.x(), n.y(), 1).normalized();

  // Sheet normal (target z, into the sheet) along the ray, then tilted about a
  // random axis perpendicular to the ray; then a random in-plane rotation.
  const Eigen::Matrix3d R_ray =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), ray).toRotationMatrix();
  const double axis_angle = 2 * kPi * unit(rng);
  const Eigen::Vector3d axis =
      R_ray * Eigen::Vector3d(std::cos(axis_angle), std::sin(axis_angle), 0);
  const Eigen::Matrix3d R_tilt(Eigen::AngleAxisd(tilt_deg * kPi / 180, axis));
  const Eigen::Matrix3d R_spin(Eigen::AngleAxisd(2 * kPi * unit(rng), Eigen::Vector3d::UnitZ()));
  vision::Pose T;
  T.R = R_tilt * R_ray * R_spin;
  T.t = distance_m * ray;
  return T;
}

// `count` poses, distances uniform over the range, tilts uniform in [0, max].
inline std::vector<vision::Pose> sample_poses(const vision::Camera& camera, int count,
                                              uint64_t seed, const PoseRange& range = {},
                                              double marker_side_m = 0.05) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<vision::Pose> poses;
  for (int i = 0; i < count; ++i) {
    const double d =
        range.min_distance_m + unit(rng) * (range.max_distance_m - range.min_distance_m);
    const double tilt = unit(rng) * range.max_tilt_deg;
    poses.push_back(sample_pose(camera, d, tilt, marker_side_m, rng));
  }
  return poses;
}

// The detector's three distance classes: 0.1-0.4, 0.4-0.7, 0.7-1.0 m (and beyond).
inline int distance_class(double distance_m) {
  return distance_m < 0.4 ? 0 : distance_m < 0.7 ? 1 : 2;
}
inline const char* distance_class_name(int c) {
  static const char* names[] = {"0.1-0.4m", "0.4-0.7m", "0.7-1.0m"};
  return names[c];
}

// RMS distance between two corner sets in the same order, pixels.
inline double corner_rms(const std::array<Eigen::Vector2d, 4>& a,
                         const std::array<Eigen::Vector2d, 4>& b) {
  double s = 0;
  for (int i = 0; i < 4; ++i)
    s += (a[i] - b[i]).squaredNorm();
  return std::sqrt(s / 4);
}

}  // namespace detector_test
