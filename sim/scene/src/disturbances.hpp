// Background clutter and occluders of the renderer (private to sim_scene).
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

namespace sim::scene::detail {

// A background of `shapes` random shapes (filled and outlined rectangles and
// quadrilaterals, ellipses, thick lines, checker patches of 3, 5, 7 or 8 cells
// with no border) over a uniform mean_reflectance, drawn antialiased.
// CV_32FC1 reflectances in [0, 1].
cv::Mat make_clutter(cv::Size size, int shapes, double mean_reflectance, std::mt19937_64& rng);

// An opaque bar (a cable, a finger) in image space.
struct Occluder {
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d axis = Eigen::Vector2d::UnitX();  // unit vector along the bar
  double half_width_px = 5;
  double half_length_px = 100;
  double reflectance = 0.3;

  // Fraction of the pixel (centre u, v) covered, with `margin_px` added to
  // both half extents: a box-filter approximation clamp(h + 0.5 - |d|, 0, 1)
  // per axis, which antialiases the bar's edges.
  double coverage(double u, double v, double margin_px = 0) const;
  // Pixel bounding box of the bar grown by margin_px, clipped to the image.
  cv::Rect bounds(cv::Size image, double margin_px) const;
};

// Draws radiance = (1 - a) * radiance + a * reflectance for each occluder.
void apply_occluders(const std::vector<Occluder>& occluders, cv::Mat& radiance);

}  // namespace sim::scene::detail
