// vision::Detector: the stages in order (see vision/detector.hpp), the input
// conversion and the bookkeeping between candidates.
#include "vision/detector.hpp"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>
#include <string>

#include "detector_internal.hpp"
#include "lens_model.hpp"

namespace vision {
namespace {

void require(bool ok, const std::string& name, const std::string& expected) {
  if (!ok) throw std::invalid_argument("detector parameter " + name + ": expected " + expected);
}

void validate(const DetectorParameters& p) {
  require(p.canny_low >= 0 && p.canny_high >= p.canny_low, "canny_low/canny_high",
          "0 <= canny_low <= canny_high");
  require(p.candidate_decimation == 1 || p.candidate_decimation == 2, "candidate_decimation",
          "1 or 2");
  require(p.canny_sigma_px >= 0 && p.canny_sigma_px <= 5, "canny_sigma_px", "in [0, 5]");
  require(p.smoothing_kernel_px >= 0 && (p.smoothing_kernel_px <= 1 || p.smoothing_kernel_px % 2),
          "smoothing_kernel_px", "0, 1 or an odd size");
  require(p.dilation_kernel_px >= 0, "dilation_kernel_px", ">= 0");
  require(p.approx_epsilon_fraction > 0 && p.approx_epsilon_fraction < 0.25,
          "approx_epsilon_fraction", "in (0, 0.25)");
  require(p.min_perimeter_px >= 16, "min_perimeter_px", ">= 16");
  require(p.max_perimeter_image_fraction > 0, "max_perimeter_image_fraction", "> 0");
  require(p.min_side_px >= 3, "min_side_px", ">= 3");
  require(p.max_abs_cos_corner >= 0 && p.max_abs_cos_corner < 1, "max_abs_cos_corner", "in [0, 1)");
  require(p.edge_search_px >= 1 && p.edge_search_px <= 20, "edge_search_px", "in [1, 20]");
  require(p.edge_refine_px >= 1 && p.edge_refine_px <= p.edge_search_px, "edge_refine_px",
          "in [1, edge_search_px]");
  require(p.edge_passes >= 1 && p.edge_passes <= 10, "edge_passes", "in [1, 10]");
  require(p.edge_sample_spacing_px > 0, "edge_sample_spacing_px", "> 0");
  require(p.max_edge_samples_per_side >= 6, "max_edge_samples_per_side", ">= 6");
  require(p.corner_exclusion_px >= 0, "corner_exclusion_px", ">= 0");
  require(p.min_relative_edge_step >= 0 && p.min_relative_edge_step <= 1, "min_relative_edge_step",
          "in [0, 1]");
  require(p.min_edge_step >= 0, "min_edge_step", ">= 0");
  require(p.min_edge_support >= 0 && p.min_edge_support <= 1, "min_edge_support", "in [0, 1]");
  require(p.max_edge_gap_px >= 0, "max_edge_gap_px", ">= 0");
  require(p.max_sample_residual_px > 0, "max_sample_residual_px", "> 0");
  require(p.max_edge_residual_px > 0, "max_edge_residual_px", "> 0");
  require(p.image_border_margin_px >= 0, "image_border_margin_px", ">= 0");
  require(p.min_edge_window_px >= 1 && p.min_edge_window_px <= p.edge_refine_px,
          "min_edge_window_px", "in [1, edge_refine_px]");
  require(p.max_corner_shift_px > 0, "max_corner_shift_px", "> 0");
  require(p.cell_sample_fraction > 0 && p.cell_sample_fraction <= 1, "cell_sample_fraction",
          "in (0, 1]");
  require(p.min_contrast >= 0, "min_contrast", ">= 0");
  require(p.min_quiet_zone_level >= 0 && p.min_quiet_zone_level <= 1, "min_quiet_zone_level",
          "in [0, 1]");
  require(p.min_cell_margin >= 0 && p.min_cell_margin < 0.5, "min_cell_margin", "in [0, 0.5)");
  require(p.max_border_errors >= 0, "max_border_errors", ">= 0");
  require(p.max_bits_corrected >= -1, "max_bits_corrected", ">= -1");
  require(p.sheet_edge_quiet_cells >= 0 && p.sheet_edge_quiet_cells <= 4, "sheet_edge_quiet_cells",
          "in [0, 4]");
}

bool point_in_quad(const detail::Quad& q, const Eigen::Vector2d& x) {
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d e = q[(i + 1) % 4] - q[i], d = x - q[i];
    if (e.x() * d.y() - e.y() * d.x() < 0) return false;  // left of a clockwise side: outside
  }
  return true;
}

Eigen::Vector2d centroid(const detail::Quad& q) {
  return 0.25 * (q[0] + q[1] + q[2] + q[3]);
}

// The marker a candidate would hold if the candidate were the edge of a
// sheet cut `quiet_cells` cells outside it: the inner 6 / (6 + 2 q) of the
// candidate, mapped through its homography in the undistorted plane (exact
// under perspective).
std::optional<detail::Quad> inset_candidate(const detail::Quad& q, const Camera& camera,
                                            int quiet_cells) {
  std::array<Eigen::Vector2d, 4> n;
  for (int i = 0; i < 4; ++i)
    if (!camera.undistort_point(q[i], &n[i])) return std::nullopt;
  const Eigen::Matrix3d H = detail::square_homography(n, 1.0);
  const double f = static_cast<double>(quiet_cells) / (kMarkerCells + 2 * quiet_cells);
  const Eigen::Vector2d uv[4] = {{f, f}, {1 - f, f}, {1 - f, 1 - f}, {f, 1 - f}};
  detail::Quad out;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d x = H * Eigen::Vector3d(uv[i].x(), uv[i].y(), 1);
    if (!(x.z() > 0)) return std::nullopt;
    out[i] = detail::distort_normalized(camera, x.head<2>() / x.z());
  }
  return out;
}

// A contour inside a detected marker (its inner rim, a code cell) is not
// another marker: markers do not nest.
bool inside_a_detection(const std::vector<detail::Quad>& accepted, const detail::Quad& candidate) {
  const Eigen::Vector2d c = centroid(candidate);
  return std::any_of(accepted.begin(), accepted.end(),
                     [&](const detail::Quad& q) { return point_in_quad(q, c); });
}

// The same marker from another contour (two nested outlines straddling its
// edge): either centroid inside the other's outline.
bool overlaps_a_detection(const std::vector<detail::Quad>& accepted, const detail::Quad& outline) {
  return std::any_of(accepted.begin(), accepted.end(), [&](const detail::Quad& q) {
    return point_in_quad(q, centroid(outline)) || point_in_quad(outline, centroid(q));
  });
}

// The candidate's sub-pixel sides; when they fail, perhaps the outline of a
// sheet cut just outside a marker, whose edge merged with the marker's in the
// dilated edge map: the marker inset by the quiet zone is tried instead.
detail::EdgeFit refine_candidate(const cv::Mat& gray, const Camera& camera,
                                 const detail::Quad& candidate, const DetectorParameters& p) {
  detail::EdgeFit fit = detail::refine_quad(gray, camera, candidate, p);
  if ((fit.status == detail::EdgeFitStatus::kSideNotSupported ||
       fit.status == detail::EdgeFitStatus::kFitFailed) &&
      p.sheet_edge_quiet_cells > 0) {
    if (const auto inner = inset_candidate(candidate, camera, p.sheet_edge_quiet_cells)) {
      const detail::EdgeFit retry = detail::refine_quad(gray, camera, *inner, p);
      if (retry.status == detail::EdgeFitStatus::kOk) fit = retry;
    }
  }
  return fit;
}

// True for a fit that succeeded; otherwise counts why it failed.
bool count_edge_fit(detail::EdgeFitStatus status, DetectorStats& s) {
  switch (status) {
    case detail::EdgeFitStatus::kOk:
      return true;
    case detail::EdgeFitStatus::kCutByImageBorder:
      ++s.cut_by_image_border;
      return false;
    case detail::EdgeFitStatus::kSideNotSupported:
      ++s.side_not_supported;
      return false;
    case detail::EdgeFitStatus::kFitFailed:
      ++s.edge_fit_failed;
      return false;
  }
  return false;
}

Detection detection_from(const detail::EdgeFit& fit, const detail::Identification& id) {
  Detection d;
  d.id = id.id;
  d.rotation = id.rotation;
  // The sampled grid has its row 0 along corners 0 -> 1. The observed grid
  // is the code turned `rotation` quarter turns clockwise, and one clockwise
  // turn carries the printed top-left corner A to the observed top-right:
  // A is the candidate's corner `rotation`.
  for (int k = 0; k < 4; ++k)
    d.corners_px[k] = fit.corners_px[(k + id.rotation) % 4];
  d.quality.contrast = id.contrast;
  d.quality.bits_corrected = id.bits_corrected;
  d.quality.edge_fit_residual_px = fit.residual_px;
  return d;
}

// By id, then by the position of corner A (row, then column).
void sort_detections(std::vector<Detection>& detections) {
  std::sort(detections.begin(), detections.end(), [](const Detection& a, const Detection& b) {
    if (a.id != b.id) return a.id < b.id;
    return std::make_pair(a.corners_px[0].y(), a.corners_px[0].x()) <
           std::make_pair(b.corners_px[0].y(), b.corners_px[0].x());
  });
}

}  // namespace

cv::Mat to_gray8(const cv::Mat& image) {
  if (image.empty()) return cv::Mat();
  cv::Mat gray;
  const int channels = image.channels();
  if (channels == 1) {
    gray = image;
  } else if (channels == 3) {
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  } else if (channels == 4) {
    cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
  } else {
    throw std::invalid_argument("image with " + std::to_string(channels) +
                                " channels (expected 1 grey, 3 BGR or 4 BGRA)");
  }
  switch (gray.depth()) {
    case CV_8U:
      return gray;
    case CV_16U:
    case CV_16S:
    case CV_32S:
    case CV_32F:
    case CV_64F: {
      // Keep the image's own range: a 12-bit camera in a 16-bit container
      // fills 0..4095, not 0..65535. Integer data up to 255 and float data
      // up to 1.0 are taken as they are.
      double lo = 0, hi = 0;
      cv::minMaxLoc(gray, &lo, &hi);
      const bool is_float = gray.depth() == CV_32F || gray.depth() == CV_64F;
      const double full = is_float ? 1.0 : 255.0;
      const double scale = hi > full ? 255.0 / hi : 255.0 / full;
      cv::Mat out;
      gray.convertTo(out, CV_8U, scale);
      return out;
    }
    default:
      throw std::invalid_argument("image of depth " + std::to_string(gray.depth()) +
                                  " (expected 8-bit, 16-bit, 32-bit integer or float)");
  }
}

Detector::Detector(const Camera& camera, const Codebook& codebook, DetectorParameters parameters)
    : camera_(camera), codebook_(codebook), parameters_(parameters) {
  validate(parameters_);
}

std::vector<Detection> Detector::detect(const cv::Mat& image, DetectorStats* stats) const {
  DetectorStats local;
  DetectorStats& s = stats ? *stats : local;
  s = DetectorStats{};
  std::vector<Detection> detections;
  const cv::Mat gray = to_gray8(image);
  // Too small to hold the smallest marker the candidate stage accepts.
  if (gray.empty() || gray.cols < 8 || gray.rows < 8) return detections;

  const auto candidates = detail::find_quad_candidates(gray, parameters_, &s);
  std::vector<detail::Quad> accepted;  // detected outlines, for suppression
  for (const auto& candidate : candidates) {
    if (inside_a_detection(accepted, candidate)) {
      ++s.suppressed;
      continue;
    }
    const detail::EdgeFit fit = refine_candidate(gray, camera_, candidate, parameters_);
    if (!count_edge_fit(fit.status, s)) continue;
    const auto id = detail::identify(gray, camera_, fit, codebook_, parameters_);
    if (!id) {
      ++s.no_code;
      continue;
    }
    // Keep the first, the larger contour.
    if (overlaps_a_detection(accepted, fit.corners_px)) {
      ++s.duplicates;
      continue;
    }
    accepted.push_back(fit.corners_px);
    detections.push_back(detection_from(fit, *id));
    ++s.detected;
  }
  sort_detections(detections);
  return detections;
}

}  // namespace vision
