// Per-pixel rays of a camera, computed once (private to sim_scene).
#pragma once

#include <vector>

#include "lens.hpp"

namespace sim::scene::detail {

// For every pixel (row-major, index v * width + u): the undistorted normalized
// point (x, y) whose projection is the pixel centre, and the Jacobian
// d(x, y)/d(u, v) there (the inverse of the lens model's Jacobian), which maps a
// sub-pixel offset to a ray offset. Pixels where the lens model cannot be
// inverted hold NaN and render as background.
struct RayTable {
  int width = 0;
  int height = 0;
  std::vector<float> x, y;                // normalized image coordinates
  std::vector<float> j00, j01, j10, j11;  // d(x, y)/d(u, v), row-major 2x2
  std::vector<float> vignetting_gain;     // 1 - vignetting * (r / r_corner)^2
};

// Newton's method per pixel, warm-started from the neighbouring pixel (the
// model is smooth), to 1e-10 px; falls back to Camera::undistort_point.
RayTable build_ray_table(const Lens& lens, double vignetting);

}  // namespace sim::scene::detail
