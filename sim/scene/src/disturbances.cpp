// Clutter and occluders (see disturbances.hpp).
#include "disturbances.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace sim::scene::detail {

namespace {

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

int grey(std::mt19937_64& rng) {
  return static_cast<int>(uniform(rng, 0.05, 0.95) * 255);
}

std::vector<cv::Point> rotated_quad(cv::Point2d c, double w, double h, double angle, double skew) {
  const double ca = std::cos(angle), sa = std::sin(angle);
  const double xs[4] = {-w / 2 + skew, w / 2 + skew, w / 2 - skew, -w / 2 - skew};
  const double ys[4] = {-h / 2, -h / 2, h / 2, h / 2};
  std::vector<cv::Point> quad;
  constexpr int kShift = 4;  // sub-pixel vertices (1/16 px) for cv drawing
  for (int i = 0; i < 4; ++i) {
    quad.emplace_back(
        static_cast<int>(std::lround((c.x + ca * xs[i] - sa * ys[i]) * (1 << kShift))),
        static_cast<int>(std::lround((c.y + sa * xs[i] + ca * ys[i]) * (1 << kShift))));
  }
  return quad;
}

}  // namespace

cv::Mat make_clutter(cv::Size size, int shapes, double mean_reflectance, std::mt19937_64& rng) {
  cv::Mat canvas(size, CV_8UC1, cv::Scalar(std::clamp(mean_reflectance, 0.0, 1.0) * 255));
  constexpr int kShift = 4;
  for (int k = 0; k < shapes; ++k) {
    const cv::Point2d c(uniform(rng, 0, size.width), uniform(rng, 0, size.height));
    const double extent = uniform(rng, 8, 0.35 * size.width);
    const double angle = uniform(rng, 0, M_PI);
    const int kind = static_cast<int>(rng() % 6);
    const cv::Scalar colour(grey(rng));
    if (kind == 0 || kind == 1) {  // filled or outlined (skewed) quadrilateral
      const auto quad = rotated_quad(c, extent, extent * uniform(rng, 0.3, 1.5), angle,
                                     kind == 1 ? uniform(rng, -0.2, 0.2) * extent : 0.0);
      if (kind == 0) {
        cv::fillConvexPoly(canvas, quad, colour, cv::LINE_AA, kShift);
      } else {
        const std::vector<std::vector<cv::Point>> polys = {quad};
        cv::polylines(canvas, polys, true, colour, static_cast<int>(uniform(rng, 1, 8)),
                      cv::LINE_AA, kShift);
      }
    } else if (kind == 2) {  // ellipse
      cv::ellipse(
          canvas, cv::Point(static_cast<int>(c.x), static_cast<int>(c.y)),
          cv::Size(static_cast<int>(extent / 2), static_cast<int>(extent * uniform(rng, 0.1, 0.5))),
          angle * 180 / M_PI, 0, 360, colour, rng() % 2 ? cv::FILLED : 3, cv::LINE_AA);
    } else if (kind == 3) {  // thick line (a cable, a table edge)
      const cv::Point2d d(std::cos(angle) * extent, std::sin(angle) * extent);
      cv::line(canvas, c - d, c + d, colour, static_cast<int>(uniform(rng, 1, 12)), cv::LINE_AA);
    } else {  // checker patch: n x n cells of random grey, no border (n != 6)
      static constexpr int kCells[] = {3, 5, 7, 8};
      const int n = kCells[rng() % 4];
      const double cell = extent / n;
      for (int r = 0; r < n; ++r) {
        for (int q = 0; q < n; ++q) {
          const cv::Point2d offset((q - n / 2.0 + 0.5) * cell, (r - n / 2.0 + 0.5) * cell);
          const cv::Point2d centre(c.x + std::cos(angle) * offset.x - std::sin(angle) * offset.y,
                                   c.y + std::sin(angle) * offset.x + std::cos(angle) * offset.y);
          cv::fillConvexPoly(canvas, rotated_quad(centre, cell, cell, angle, 0),
                             cv::Scalar(rng() % 2 ? 230 : 25), cv::LINE_AA, kShift);
        }
      }
    }
  }
  cv::Mat out;
  canvas.convertTo(out, CV_32FC1, 1.0 / 255);
  return out;
}

double Occluder::coverage(double u, double v, double margin_px) const {
  const Eigen::Vector2d d(u - centre_px.x(), v - centre_px.y());
  const double along = std::abs(d.dot(axis));
  const double across = std::abs(axis.x() * d.y() - axis.y() * d.x());
  const double a = std::clamp(half_length_px + margin_px + 0.5 - along, 0.0, 1.0);
  const double b = std::clamp(half_width_px + margin_px + 0.5 - across, 0.0, 1.0);
  return a * b;
}

cv::Rect Occluder::bounds(cv::Size image, double margin_px) const {
  const Eigen::Vector2d normal(-axis.y(), axis.x());
  const double hl = half_length_px + margin_px + 1, hw = half_width_px + margin_px + 1;
  const double ex = std::abs(axis.x()) * hl + std::abs(normal.x()) * hw;
  const double ey = std::abs(axis.y()) * hl + std::abs(normal.y()) * hw;
  const int x0 = std::max(0, static_cast<int>(std::floor(centre_px.x() - ex)));
  const int y0 = std::max(0, static_cast<int>(std::floor(centre_px.y() - ey)));
  const int x1 = std::min(image.width, static_cast<int>(std::ceil(centre_px.x() + ex)) + 1);
  const int y1 = std::min(image.height, static_cast<int>(std::ceil(centre_px.y() + ey)) + 1);
  if (x1 <= x0 || y1 <= y0) return {};
  return {x0, y0, x1 - x0, y1 - y0};
}

void apply_occluders(const std::vector<Occluder>& occluders, cv::Mat& radiance) {
  for (const Occluder& o : occluders) {
    const cv::Rect box = o.bounds(radiance.size(), 0);
    for (int v = box.y; v < box.y + box.height; ++v) {
      float* row = radiance.ptr<float>(v);
      for (int u = box.x; u < box.x + box.width; ++u) {
        const double a = o.coverage(u, v);
        if (a > 0) row[u] = static_cast<float>((1 - a) * row[u] + a * o.reflectance);
      }
    }
  }
}

}  // namespace sim::scene::detail
