// Quadrilateral candidates: the paper's detection steps 1-7 (Maidi et al.
// 2010, §3): Canny, Gaussian smoothing of the edge map, dilation, contour
// approximation proportional to the perimeter, four vertices, convexity and
// near-right corner angles.
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "detector_internal.hpp"

namespace vision::detail {
namespace {

// Largest |cos| of the four corner angles of a quadrilateral.
double max_abs_corner_cos(const Quad& q) {
  double worst = 0;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d a = q[(i + 3) % 4] - q[i];
    const Eigen::Vector2d b = q[(i + 1) % 4] - q[i];
    worst = std::max(worst, std::abs(a.dot(b)) / (a.norm() * b.norm()));
  }
  return worst;
}

// Visually clockwise in the image (y down) <=> positive z of (q1-q0) x (q2-q1).
void make_clockwise(Quad* q) {
  double area2 = 0;
  for (int i = 0; i < 4; ++i) {
    const auto& a = (*q)[i];
    const auto& b = (*q)[(i + 1) % 4];
    area2 += a.x() * b.y() - b.x() * a.y();
  }
  if (area2 < 0) std::swap((*q)[1], (*q)[3]);
}

}  // namespace

void close_edge_gaps(const DetectorParameters& p, int decimation, cv::Mat* edges) {
  // findContours sees only which pixels are non-zero, and a 3x3 Gaussian of
  // a 0/255 edge map is non-zero exactly on the kernel's footprint (its
  // smallest weight, 1/16, gives 16 grey levels): so the two steps are one
  // dilation by their Minkowski sum, a square of smooth + grow - 1 px, at a
  // third of the cost. The kernels are in full-resolution pixels; with
  // decimation the square shrinks by it, rounded up to an odd size.
  const auto scaled = [decimation](int k) {
    return k <= 1 ? 1 : ((k + decimation - 1) / decimation) | 1;
  };
  const int smooth = std::max(p.smoothing_kernel_px, 1), grow = std::max(p.dilation_kernel_px, 1);
  if (smooth > 3) {
    cv::GaussianBlur(*edges, *edges, cv::Size(scaled(smooth), scaled(smooth)), 0);
    if (scaled(grow) > 1) dilate_square(*edges, scaled(grow), edges);
  } else if (scaled(smooth + grow - 1) > 1) {
    dilate_square(*edges, scaled(smooth + grow - 1), edges);
  }
}

std::vector<Quad> find_quad_candidates(const cv::Mat& gray, const DetectorParameters& p,
                                       DetectorStats* stats) {
  // Step 1: Canny's operator, whose first stage is a Gaussian smoothing of
  // the image (Canny 1986; cv::Canny itself starts at the Sobel gradient).
  // With decimation, cv::pyrDown's 5x5 Gaussian is that stage (half_image:
  // the same pixels), and the candidates are found at half resolution (a
  // quarter of the pixels).
  cv::Mat edges;
  const int d = p.candidate_decimation;
  if (d == 2) {
    cv::Mat half;
    half_image(gray, &half);
    canny_edges(half, p, &edges);
  } else if (p.canny_sigma_px > 0) {
    const int k = 2 * static_cast<int>(std::ceil(2.5 * p.canny_sigma_px)) + 1;  // +-2.5 sigma
    cv::Mat smoothed;
    cv::GaussianBlur(gray, smoothed, cv::Size(k, k), p.canny_sigma_px);
    canny_edges(smoothed, p, &edges);
  } else {
    canny_edges(gray, p, &edges);
  }
  // Step 2: smoothing joins edge pixels a pixel apart; step 3: dilation
  // closes the remaining holes.
  close_edge_gaps(p, d, &edges);

  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(edges, contours, cv::RETR_LIST, cv::CHAIN_APPROX_SIMPLE);
  stats->contours = static_cast<int>(contours.size());

  const double max_perimeter = p.max_perimeter_image_fraction * (gray.cols + gray.rows);
  std::vector<std::pair<double, Quad>> found;
  std::vector<cv::Point> approx;
  for (const auto& contour : contours) {
    if (contour.size() < 4) continue;
    // Step 4: approximation tolerance proportional to the perimeter.
    const double perimeter = d * cv::arcLength(contour, true);  // full-resolution pixels
    if (perimeter < p.min_perimeter_px || perimeter > max_perimeter) continue;
    cv::approxPolyDP(contour, approx, p.approx_epsilon_fraction * perimeter / d, true);
    // Steps 5-6: four vertices bounding a convex region (four intersecting lines).
    if (approx.size() != 4 || !cv::isContourConvex(approx)) continue;
    Quad q;
    for (int i = 0; i < 4; ++i)
      q[i] = d * Eigen::Vector2d(approx[i].x, approx[i].y);  // pyrDown: (x, y) -> (2x, 2y)
    double shortest = 1e300;
    for (int i = 0; i < 4; ++i)
      shortest = std::min(shortest, (q[(i + 1) % 4] - q[i]).norm());
    if (shortest < p.min_side_px) continue;
    // Step 7: the cosines of the four angles near zero.
    if (max_abs_corner_cos(q) > p.max_abs_cos_corner) continue;
    make_clockwise(&q);
    found.emplace_back(perimeter, q);
  }
  // Largest first: a marker's outer outline comes before the contours inside
  // it (its inner rim, its code cells), which the detector then skips.
  std::stable_sort(found.begin(), found.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<Quad> quads;
  quads.reserve(found.size());
  for (const auto& f : found)
    quads.push_back(f.second);
  stats->candidates = static_cast<int>(quads.size());
  return quads;
}

}  // namespace vision::detail
