// Internals of vision::Detector shared by its three stages (not installed):
// quadrilateral candidates (detector_quads.cpp), sub-pixel sides
// (detector_edges.cpp) and identification (detector_identify.cpp).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "cpu_builds.hpp"
#include "vision/camera.hpp"
#include "vision/codebook.hpp"
#include "vision/detector.hpp"

namespace vision::detail {

// Four image points, visually clockwise in the image (x right, y down), so
// that for every side q[i] -> q[i+1] the marker lies to the right.
using Quad = std::array<Eigen::Vector2d, 4>;

// Bilinear interpolation of an 8-bit grey image at (x, y), OpenCV pixel
// convention. Precondition: 0 <= x <= cols - 1 and 0 <= y <= rows - 1
// (callers check the margin once per side, not per sample).
inline double sample_bilinear(const cv::Mat& gray, double x, double y) {
  const int x0 = std::min(static_cast<int>(x), gray.cols - 2);
  const int y0 = std::min(static_cast<int>(y), gray.rows - 2);
  const double fx = x - x0, fy = y - y0;
  const uint8_t* r0 = gray.ptr<uint8_t>(y0) + x0;
  const uint8_t* r1 = r0 + gray.step[0];
  const double top = r0[0] + fx * (r0[1] - r0[0]);
  const double bottom = r1[0] + fx * (r1[1] - r1[0]);
  return top + fy * (bottom - top);
}

inline bool inside_image(const cv::Mat& gray, const Eigen::Vector2d& p, double margin) {
  return p.x() >= margin && p.y() >= margin && p.x() <= gray.cols - 1 - margin &&
         p.y() <= gray.rows - 1 - margin;
}

// The candidate stage's pixel loops (half_image, canny_edges, dilate_square)
// are plain element-wise loops that the compiler vectorizes, built for the
// baseline instruction set and for AVX2 (cpu_builds.hpp); allow_avx2 = false
// keeps to the baseline one.

// The image halved for the candidate stage: cv::pyrDown(gray, *half), pixel
// for pixel (tests/vision/detector_edge_map_test.cpp), in less time for
// 8-bit grey images of at least 4x4 pixels (anything else goes to
// cv::pyrDown).
void half_image(const cv::Mat& gray, cv::Mat* half, bool allow_avx2 = true);

// Step 1's edge map of an 8-bit grey image: cv::Canny(image, *edges,
// canny_low, canny_high, 3, false), bit for bit (tests/vision/
// detector_edge_map_test.cpp), in less time. allow_avx2 as half_image's.
// Precondition: image is CV_8UC1 and not empty (cv::Exception otherwise).
void canny_edges(const cv::Mat& image, const DetectorParameters& p, cv::Mat* edges,
                 bool allow_avx2 = true);

// cv::dilate(image, *dilated, a k x k MORPH_RECT), value for value
// (tests/vision/detector_edge_map_test.cpp), in less time, for 8-bit grey
// images. Precondition: k odd and >= 1, image CV_8UC1 and not empty
// (cv::Exception otherwise). dilated may be image.
void dilate_square(const cv::Mat& image, int k, cv::Mat* dilated, bool allow_avx2 = true);

// Steps 2-3 on the edge map of the image reduced `decimation` (1 or 2) times:
// the smoothing (smoothing_kernel_px) and the dilation (dilation_kernel_px),
// both sizes in full-resolution pixels. Only which pixels end non-zero is
// defined, which is all findContours reads: at decimation 1, exactly those of
// cv::GaussianBlur by the one kernel then cv::dilate by the other.
void close_edge_gaps(const DetectorParameters& p, int decimation, cv::Mat* edges);

// Steps 1-7 of the paper: convex, near-right-angled quadrilaterals, largest
// perimeter first. Fills stats->contours and stats->candidates.
std::vector<Quad> find_quad_candidates(const cv::Mat& gray, const DetectorParameters& p,
                                       DetectorStats* stats);

enum class EdgeFitStatus { kOk, kCutByImageBorder, kSideNotSupported, kFitFailed };

struct EdgeFit {
  EdgeFitStatus status = EdgeFitStatus::kFitFailed;
  Quad corners_px;                              // refined, distorted pixels, same order as input
  std::array<Eigen::Vector2d, 4> corners_norm;  // the same in the undistorted normalized plane
  double residual_px = 0;                       // RMS of the edge samples about their lines
};

// Sub-pixel sides and corners from a candidate (stage 8).
EdgeFit refine_quad(const cv::Mat& gray, const Camera& camera, const Quad& candidate,
                    const DetectorParameters& p);

// H with H * (u, v, 1) ~ (x, y, 1) mapping the square [0, side]^2 (corners
// (0,0), (side,0), (side,side), (0,side)) onto the quadrilateral x (DLT with
// h33 = 1). In the undistorted normalized plane this is eq. 30 exactly.
Eigen::Matrix3d square_homography(const std::array<Eigen::Vector2d, 4>& x, double side);

struct Identification {
  int id = -1;
  int rotation = 0;
  int bits_corrected = 0;
  double contrast = 0;
};

// Reads the 6x6 grid through the homography of the refined corners (eq. 30)
// and decodes it; std::nullopt when the contrast, the border or the code fails.
std::optional<Identification> identify(const cv::Mat& gray, const Camera& camera,
                                       const EdgeFit& fit, const Codebook& codebook,
                                       const DetectorParameters& p);

}  // namespace vision::detail
