// Per-pixel ray table (see rays.hpp).
#include "rays.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

namespace sim::scene::detail {

namespace {

// Inverts the lens model at one pixel from an initial guess; true when the
// re-distorted point is within tolerance_px of the pixel.
bool newton_undistort(const Lens& lens, const Eigen::Vector2d& pixel, Eigen::Vector2d* xy) {
  constexpr double kTolerancePx = 1e-10;
  for (int iteration = 0; iteration < 20; ++iteration) {
    const Eigen::Vector2d residual = lens.distort_normalized(*xy) - pixel;
    if (residual.norm() < kTolerancePx) return true;
    const Eigen::Matrix2d J = lens.distort_jacobian(*xy);
    *xy -= J.inverse() * residual;
    if (!xy->allFinite()) return false;
  }
  return (lens.distort_normalized(*xy) - pixel).norm() < kTolerancePx;
}

}  // namespace

RayTable build_ray_table(const Lens& lens, double vignetting) {
  const vision::Camera& camera = lens.camera();
  RayTable t;
  t.width = camera.width_px();
  t.height = camera.height_px();
  const size_t n = static_cast<size_t>(t.width) * static_cast<size_t>(t.height);
  for (auto* v : {&t.x, &t.y, &t.j00, &t.j01, &t.j10, &t.j11, &t.vignetting_gain})
    v->resize(n);

  const auto& k = camera.intrinsics();
  const double r_corner = std::max({std::hypot(k.cx, k.cy), std::hypot(t.width - 1 - k.cx, k.cy),
                                    std::hypot(k.cx, t.height - 1 - k.cy),
                                    std::hypot(t.width - 1 - k.cx, t.height - 1 - k.cy)});
  const float nan = std::numeric_limits<float>::quiet_NaN();
  Eigen::Vector2d row_start((0 - k.cx) / k.fx, (0 - k.cy) / k.fy);
  for (int v = 0; v < t.height; ++v) {
    Eigen::Vector2d guess = row_start;
    for (int u = 0; u < t.width; ++u) {
      const size_t i =
          static_cast<size_t>(v) * static_cast<size_t>(t.width) + static_cast<size_t>(u);
      const Eigen::Vector2d pixel(u, v);
      Eigen::Vector2d xy = guess;
      bool ok = newton_undistort(lens, pixel, &xy);
      if (!ok) {
        // The Brown-Conrady inverse, then Newton again for the prism terms.
        ok = camera.undistort_point(pixel, &xy) &&
             (!lens.has_prism() || newton_undistort(lens, pixel, &xy));
      }
      const double r = std::hypot(u - k.cx, v - k.cy) / r_corner;
      t.vignetting_gain[i] = static_cast<float>(1.0 - vignetting * r * r);
      if (!ok) {
        t.x[i] = t.y[i] = t.j00[i] = t.j01[i] = t.j10[i] = t.j11[i] = nan;
        guess = Eigen::Vector2d((u + 1 - k.cx) / k.fx, (v - k.cy) / k.fy);
        continue;
      }
      if (u == 0) row_start = xy;
      guess = xy;
      const Eigen::Matrix2d Jinv = lens.distort_jacobian(xy).inverse();
      t.x[i] = static_cast<float>(xy.x());
      t.y[i] = static_cast<float>(xy.y());
      t.j00[i] = static_cast<float>(Jinv(0, 0));
      t.j01[i] = static_cast<float>(Jinv(0, 1));
      t.j10[i] = static_cast<float>(Jinv(1, 0));
      t.j11[i] = static_cast<float>(Jinv(1, 1));
    }
  }
  return t;
}

}  // namespace sim::scene::detail
