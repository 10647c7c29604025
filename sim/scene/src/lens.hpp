// The renderer's true lens: vision::Camera's model plus the thin-prism terms
// of SceneOptions::thin_prism and the radial r^8 term of
// SceneOptions::radial_k4 (private to sim_scene). vision::Camera has no r^8
// term, so a lens with one is never fitted exactly by a calibration, as with
// a real lens.
//
// Thin prism (Weng, Cohen & Herniou, "Camera calibration with distortion
// models and accuracy evaluation", IEEE PAMI 14(10), 1992; OpenCV's s1..s4)
// and radial r^8 (Brown 1971, the fourth term of the radial series):
//   xd += s1 r2 + s2 r2^2 + x k4 r2^4,  yd += s3 r2 + s4 r2^2 + y k4 r2^4,
// r2 = x^2 + y^2, added to the camera's (xd, yd) before the intrinsics.
#pragma once

#include <Eigen/Core>
#include <array>

#include "vision/camera.hpp"

namespace sim::scene::detail {

class Lens {
 public:
  Lens(const vision::Camera& camera, const std::array<double, 4>& thin_prism, double radial_k4 = 0)
      : camera_(camera), s_(thin_prism), k4_(radial_k4) {}

  // Whether the lens has a term beyond the camera's model.
  bool has_prism() const {
    return s_[0] != 0 || s_[1] != 0 || s_[2] != 0 || s_[3] != 0 || k4_ != 0;
  }

  // Undistorted normalized point -> distorted pixels (OpenCV convention).
  Eigen::Vector2d distort_normalized(const Eigen::Vector2d& xy) const {
    Eigen::Vector2d px = camera_.distort_normalized(xy);
    if (!has_prism()) return px;
    const double r2 = xy.squaredNorm();
    const auto& k = camera_.intrinsics();
    const double r8 = r2 * r2 * r2 * r2;
    px.x() += k.fx * (s_[0] * r2 + s_[1] * r2 * r2 + xy.x() * k4_ * r8);
    px.y() += k.fy * (s_[2] * r2 + s_[3] * r2 * r2 + xy.y() * k4_ * r8);
    return px;
  }

  // d(pixel)/d(normalized point), 2x2.
  Eigen::Matrix2d distort_jacobian(const Eigen::Vector2d& xy) const {
    Eigen::Matrix2d J = camera_.distort_jacobian(xy);
    if (!has_prism()) return J;
    const double r2 = xy.squaredNorm();
    const auto& k = camera_.intrinsics();
    // d(s r2 + s' r2^2)/dx = (s + 2 s' r2) 2x, likewise for y.
    const double gx = s_[0] + 2 * s_[1] * r2, gy = s_[2] + 2 * s_[3] * r2;
    J(0, 0) += k.fx * gx * 2 * xy.x();
    J(0, 1) += k.fx * gx * 2 * xy.y();
    J(1, 0) += k.fy * gy * 2 * xy.x();
    J(1, 1) += k.fy * gy * 2 * xy.y();
    // d(x k4 r2^4)/dx = k4 (r2^4 + 8 x^2 r2^3), d/dy = 8 k4 x y r2^3; likewise for y.
    const double r6 = r2 * r2 * r2, x = xy.x(), y = xy.y();
    J(0, 0) += k.fx * k4_ * (r6 * r2 + 8 * x * x * r6);
    J(0, 1) += k.fx * k4_ * 8 * x * y * r6;
    J(1, 0) += k.fy * k4_ * 8 * x * y * r6;
    J(1, 1) += k.fy * k4_ * (r6 * r2 + 8 * y * y * r6);
    return J;
  }

  // Camera-frame point (metres, z > 0) -> distorted pixels.
  Eigen::Vector2d project(const Eigen::Vector3d& p_cam) const {
    if (!has_prism()) return camera_.project(p_cam);
    return distort_normalized(Eigen::Vector2d(p_cam.x() / p_cam.z(), p_cam.y() / p_cam.z()));
  }

  const vision::Camera& camera() const { return camera_; }

 private:
  vision::Camera camera_;
  std::array<double, 4> s_;
  double k4_;
};

}  // namespace sim::scene::detail
