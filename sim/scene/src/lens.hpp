// The renderer's true lens: vision::Camera's Brown-Conrady model plus the
// thin-prism terms of SceneOptions::thin_prism (private to sim_scene). The
// pose solvers' model (vision::Camera) stays the 5-parameter one, so a lens
// with prism terms is never fitted exactly by a calibration, as with a real
// lens.
//
// Thin prism (Weng, Cohen & Herniou, "Camera calibration with distortion
// models and accuracy evaluation", IEEE PAMI 14(10), 1992; OpenCV's s1..s4):
//   xd += s1 r2 + s2 r2^2,  yd += s3 r2 + s4 r2^2,  r2 = x^2 + y^2,
// added to the Brown-Conrady (xd, yd) before the intrinsics.
#pragma once

#include <Eigen/Core>
#include <array>

#include "vision/camera.hpp"

namespace sim::scene::detail {

class Lens {
 public:
  Lens(const vision::Camera& camera, const std::array<double, 4>& thin_prism)
      : camera_(camera), s_(thin_prism) {}

  bool has_prism() const { return s_[0] != 0 || s_[1] != 0 || s_[2] != 0 || s_[3] != 0; }

  // Undistorted normalized point -> distorted pixels (OpenCV convention).
  Eigen::Vector2d distort_normalized(const Eigen::Vector2d& xy) const {
    Eigen::Vector2d px = camera_.distort_normalized(xy);
    if (!has_prism()) return px;
    const double r2 = xy.squaredNorm();
    const auto& k = camera_.intrinsics();
    px.x() += k.fx * (s_[0] * r2 + s_[1] * r2 * r2);
    px.y() += k.fy * (s_[2] * r2 + s_[3] * r2 * r2);
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
};

}  // namespace sim::scene::detail
