// The lens model's forward map, from the undistorted normalized plane to
// pixels, and its Jacobian: the bodies of Camera::distort_normalized and
// Camera::distort_jacobian (vision/camera.hpp), inline so that the
// detector's per-sample loops (edge profiles, cell lattices) compile them
// into their own code instead of calling out for twenty multiplications.
#pragma once

#include <Eigen/Core>

#include "vision/camera.hpp"

namespace vision::detail {

// Distorted pixel of the normalized point xy = (X/Z, Y/Z).
inline Eigen::Vector2d distort_normalized(const Intrinsics& k, const Distortion& d,
                                          const Eigen::Vector2d& xy) {
  const double x = xy.x(), y = xy.y();
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  const double xd =
      x * radial + 2 * d.p1 * x * y + d.p2 * (r2 + 2 * x * x) + r2 * (d.s1 + d.s2 * r2);
  const double yd =
      y * radial + d.p1 * (r2 + 2 * y * y) + 2 * d.p2 * x * y + r2 * (d.s3 + d.s4 * r2);
  return {k.fx * xd + k.cx, k.fy * yd + k.cy};
}

inline Eigen::Vector2d distort_normalized(const Camera& camera, const Eigen::Vector2d& xy) {
  return distort_normalized(camera.intrinsics(), camera.distortion(), xy);
}

// d(pixel)/d(normalized point) of distort_normalized at xy, 2x2.
inline Eigen::Matrix2d distort_jacobian(const Intrinsics& k, const Distortion& d,
                                        const Eigen::Vector2d& xy) {
  const double x = xy.x(), y = xy.y();
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  // d(radial)/d(r2), and d(r2)/dx = 2x, d(r2)/dy = 2y.
  const double dradial = d.k1 + r2 * (2 * d.k2 + 3 * d.k3 * r2);
  Eigen::Matrix2d j;
  j(0, 0) = radial + x * dradial * 2 * x + 2 * d.p1 * y + d.p2 * 6 * x;
  j(0, 1) = x * dradial * 2 * y + 2 * d.p1 * x + d.p2 * 2 * y;
  j(1, 0) = y * dradial * 2 * x + d.p1 * 2 * x + 2 * d.p2 * y;
  j(1, 1) = radial + y * dradial * 2 * y + d.p1 * 6 * y + 2 * d.p2 * x;
  // Thin prism: d(s r2 + s' r2^2)/dx = (s + 2 s' r2) 2x, likewise for y.
  const double gx = d.s1 + 2 * d.s2 * r2, gy = d.s3 + 2 * d.s4 * r2;
  j(0, 0) += gx * 2 * x;
  j(0, 1) += gx * 2 * y;
  j(1, 0) += gy * 2 * x;
  j(1, 1) += gy * 2 * y;
  j.row(0) *= k.fx;
  j.row(1) *= k.fy;
  return j;
}

inline Eigen::Matrix2d distort_jacobian(const Camera& camera, const Eigen::Vector2d& xy) {
  return distort_jacobian(camera.intrinsics(), camera.distortion(), xy);
}

}  // namespace vision::detail
