// Sub-pixel sides of a candidate quadrilateral, with the lens distortion
// accounted for.
//
// A side of the printed square is straight on the sheet, hence straight in
// the undistorted normalized image plane (x, y) = (X/Z, Y/Z), and a curve in
// the distorted image. Each side is sampled along its straight segment in the
// normalized plane; every sample is distorted into the image (Camera::
// distort_normalized), where the intensity profile across the edge is read
// along the image normal of the curve. The edge position on each profile is
// the "equal area" position of an ideal step with the same end levels,
//   s_edge = s_start + (I_end * L - integral of I over the window) / (I_end - I_start),
// which is exact for any symmetric blur (optics, pixel area, bilinear
// interpolation) when the window spans the transition, and which, unlike the
// peak of a sampled derivative, does not lock onto pixel positions. The edge
// points go back to the normalized plane through the inverse of the local
// distortion Jacobian (the offsets are < 3 px, where the linearization error
// is below 1e-3 px), are fitted by a straight line (total least squares, with
// outliers removed), and adjacent lines are intersected into corners, which
// are distorted back to pixels. The first pass searches widely around the
// contour polygon (peak of the dark-to-bright derivative); later passes
// re-centre narrow windows on the fitted curves.
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "detector_internal.hpp"
#include "lens_model.hpp"

namespace vision::detail {
namespace {

constexpr double kProfileStepPx = 0.5;

struct Line {
  Eigen::Vector2d normal = Eigen::Vector2d::UnitX();  // unit, in the normalized plane
  double offset = 0;                                  // normal . x = offset
};

struct Sample {
  Eigen::Vector2d point_norm = Eigen::Vector2d::Zero();  // edge point, normalized plane
  // d(pixel)/d(normalized point) at the sample's point on the side, and the
  // image displacement of a unit normalized step along the line normal (J n).
  Eigen::Matrix2d jacobian = Eigen::Matrix2d::Identity();
  Eigen::Vector2d jac_normal = Eigen::Vector2d::Zero();
  double step = 0;  // dark-to-bright step of the profile, grey levels
  bool valid = false;
};

struct SideFit {
  EdgeFitStatus status = EdgeFitStatus::kFitFailed;
  Line line;
  double sum_sq_residual_px = 0;
  int inliers = 0;
};

// std::llround(v) for |v| < 2^63, inline (std::llround is a libm call, five
// of them a profile): v - trunc(v) is exact, so the half-way test is too.
std::int64_t round_half_away(double v) {
  const auto whole = static_cast<std::int64_t>(v);
  const double fraction = v - static_cast<double>(whole);
  return fraction >= 0.5 ? whole + 1 : fraction <= -0.5 ? whole - 1 : whole;
}

// Reads the profile through `centre` along `normal` (image, unit, outward) at
// offsets -inner .. +outer, bilinearly interpolated (sample_bilinear's
// convention). The samples lie on a line at a constant step, so the position
// advances in fixed point (32 fractional bits: under 1e-8 px of drift over a
// profile) and the interpolation runs on integers with weights rounded to 16
// bits (within 2 x 255 / 2^17 = 0.004 grey levels of the exact value: far
// below the sensor's noise). Precondition: every sample inside the image
// (edge_window).
void read_profile(const cv::Mat& gray, const Eigen::Vector2d& centre, const Eigen::Vector2d& normal,
                  double inner, double outer, std::vector<double>* values) {
  const int n = static_cast<int>(round_half_away((inner + outer) / kProfileStepPx)) + 1;
  values->resize(n);
  constexpr double kOne = 4294967296.0;  // 2^32
  const Eigen::Vector2d start = centre - inner * normal;
  // Half a weight unit ahead, so that truncating to 16 bits rounds.
  constexpr std::int64_t kHalfWeight = std::int64_t{1} << 15;
  std::int64_t x = round_half_away(start.x() * kOne) + kHalfWeight;
  std::int64_t y = round_half_away(start.y() * kOne) + kHalfWeight;
  const std::int64_t dx = round_half_away(kProfileStepPx * normal.x() * kOne);
  const std::int64_t dy = round_half_away(kProfileStepPx * normal.y() * kOne);
  const std::int64_t last_col = gray.cols - 2, last_row = gray.rows - 2;
  const std::size_t stride = gray.step[0];
  const std::uint8_t* const data = gray.data;
  double* const out = values->data();
  for (int j = 0; j < n; ++j, x += dx, y += dy) {
    std::int64_t x0 = x >> 32, y0 = y >> 32;
    std::int64_t fx = (x >> 16) & 0xFFFF, fy = (y >> 16) & 0xFFFF;
    if (x0 > last_col) x0 = last_col, fx = 0x10000;  // on the last column
    if (y0 > last_row) y0 = last_row, fy = 0x10000;
    const std::uint8_t* r0 = data + y0 * stride + x0;
    const std::uint8_t* r1 = r0 + stride;
    const std::int64_t top = (std::int64_t{r0[0]} << 16) + fx * (r0[1] - r0[0]);
    const std::int64_t bottom = (std::int64_t{r1[0]} << 16) + fx * (r1[1] - r1[0]);
    out[j] = static_cast<double>((top << 16) + fy * (bottom - top)) * (1.0 / kOne);
  }
}

// How far from `from` along the unit `direction` (at most `reach` pixels, in
// whole profile steps) the image holds samples `margin` inside its border;
// negative when `from` itself is not.
double reach_inside(const cv::Mat& gray, const Eigen::Vector2d& from,
                    const Eigen::Vector2d& direction, double reach, double margin) {
  if (!inside_image(gray, from, margin)) return -1;
  const double hi[2] = {gray.cols - 1 - margin, gray.rows - 1 - margin};
  double s = reach;
  // Most profiles lie far from the border: a unit direction moves at most
  // `reach` along each axis, so the whole reach is inside.
  if (from.x() - reach >= margin && from.y() - reach >= margin && from.x() + reach <= hi[0] &&
      from.y() + reach <= hi[1])
    return std::floor(s / kProfileStepPx + 1e-9) * kProfileStepPx;
  for (int a = 0; a < 2; ++a) {
    if (direction[a] > 1e-12) s = std::min(s, (hi[a] - from[a]) / direction[a]);
    if (direction[a] < -1e-12) s = std::min(s, (margin - from[a]) / direction[a]);
  }
  return std::floor(s / kProfileStepPx + 1e-9) * kProfileStepPx;
}

// The window -inner .. +outer across an edge at `centre`: `half` each way,
// cut where the image ends (a marker near the border). False when either
// side keeps less than min_edge_window_px: the edge's plateaus, and so its
// position, would not be measured.
bool edge_window(const cv::Mat& gray, const Eigen::Vector2d& centre, const Eigen::Vector2d& normal,
                 double half, const DetectorParameters& p, double* inner, double* outer) {
  *inner = reach_inside(gray, centre, -normal, half, p.image_border_margin_px);
  *outer = reach_inside(gray, centre, normal, half, p.image_border_margin_px);
  return *inner >= p.min_edge_window_px && *outer >= p.min_edge_window_px;
}

// Equal-area edge position on a profile starting at s0 (see the file comment),
// with the end levels averaged over the outer `ends` samples of each side.
// Returns false when the profile (n values from v) does not rise.
bool equal_area_edge(const double* v, int n, double s0, double* s_edge, double* step) {
  constexpr int ends = 2;
  double lo = 0, hi = 0;
  for (int j = 0; j < ends; ++j) {
    lo += v[j];
    hi += v[n - 1 - j];
  }
  lo /= ends;
  hi /= ends;
  *step = hi - lo;
  if (!(*step > 0)) return false;
  // Trapezoid integral over the window [s0, s0 + L].
  double area = 0;
  for (int j = 0; j + 1 < n; ++j)
    area += 0.5 * (v[j] + v[j + 1]) * kProfileStepPx;
  const double length = (n - 1) * kProfileStepPx;
  *s_edge = s0 + (hi * length - area) / *step;
  return *s_edge > s0 && *s_edge < s0 + length;
}

// Total least squares line through the valid samples.
bool fit_line(const std::vector<Sample>& samples, Line* line) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  int n = 0;
  for (const auto& s : samples)
    if (s.valid) {
      mean += s.point_norm;
      ++n;
    }
  if (n < 3) return false;
  mean /= n;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& s : samples)
    if (s.valid) {
      const Eigen::Vector2d d = s.point_norm - mean;
      cov += d * d.transpose();
    }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  line->normal = eig.eigenvectors().col(0);  // smallest eigenvalue: across the line
  line->offset = line->normal.dot(mean);
  return line->normal.allFinite();
}

// Residual of a sample about a line, in image pixels.
double residual_px(const Sample& s, const Line& line) {
  return (line.normal.dot(s.point_norm) - line.offset) * s.jac_normal.norm();
}

// Where a side is read: m samples at t0..t1 of the way from corner n0 to n1
// (normalized plane), each across the edge over +-half image pixels.
struct SideSampling {
  Eigen::Vector2d n0, n1, dn;  // the corners, and the side n1 - n0
  double t0 = 0, t1 = 1;
  int m = 0;
  double half = 0;
  bool first_pass = false;

  Eigen::Vector2d point(int k) const {
    const double t = t0 + (t1 - t0) * k / (m - 1);
    return n0 + t * dn;
  }
};

SideSampling plan_side(const Eigen::Vector2d& n0, const Eigen::Vector2d& n1, double length_px,
                       bool first_pass, const DetectorParameters& p) {
  SideSampling s;
  const double exclusion = std::min(p.corner_exclusion_px, 0.2 * length_px);
  s.t0 = exclusion / length_px;
  s.t1 = 1 - s.t0;
  // The first pass only has to find the edge near the contour: it reads a
  // quarter of the samples (each over a wider window); later passes use them all.
  const int max_samples =
      first_pass ? std::max(6, p.max_edge_samples_per_side / 4) : p.max_edge_samples_per_side;
  s.m = std::clamp(static_cast<int>((s.t1 - s.t0) * length_px / p.edge_sample_spacing_px) + 1, 6,
                   max_samples);
  s.half = first_pass ? p.edge_search_px : p.edge_refine_px;
  s.first_pass = first_pass;
  s.n0 = n0;
  s.n1 = n1;
  s.dn = n1 - n0;
  return s;
}

// The edge on the profile through `px` along `normal` (already read into
// `profile`): its offset from px along the normal (image pixels) and its
// step. The first pass takes the strongest dark-to-bright rise, then the
// equal-area position in a window of edge_refine_px around it. False when no
// edge is found or the window leaves the image.
bool locate_edge(const cv::Mat& gray, const Eigen::Vector2d& px, const Eigen::Vector2d& normal,
                 const SideSampling& side, double inner, const DetectorParameters& p,
                 const std::vector<double>& profile, double* s_edge, double* step) {
  if (!side.first_pass)
    return equal_area_edge(profile.data(), static_cast<int>(profile.size()), -inner, s_edge, step);
  int best = 0;
  double best_d = -1;
  for (size_t i = 0; i + 1 < profile.size(); ++i) {
    const double d = profile[i + 1] - profile[i];
    if (d > best_d) best_d = d, best = static_cast<int>(i);
  }
  // The window is centred on the profile sample after the steepest rise (on
  // the profile's own grid, half a step past the rise's midpoint: the
  // equal-area position does not depend on where the window is centred as
  // long as it spans the edge), so when it lies inside the wide profile its
  // samples are the profile's own and nothing is read twice.
  const int centre = best + 1;
  const int half = static_cast<int>(round_half_away(p.edge_refine_px / kProfileStepPx));
  const double s_peak = -inner + centre * kProfileStepPx;
  if (centre - half >= 0 && centre + half < static_cast<int>(profile.size())) {
    const bool ok = equal_area_edge(profile.data() + (centre - half), 2 * half + 1,
                                    -half * kProfileStepPx, s_edge, step);
    *s_edge += s_peak;
    return ok;
  }
  const Eigen::Vector2d c = px + s_peak * normal;
  double window_inner = 0, window_outer = 0;
  if (!edge_window(gray, c, normal, p.edge_refine_px, p, &window_inner, &window_outer))
    return false;
  std::vector<double> window;
  read_profile(gray, c, normal, window_inner, window_outer, &window);
  const bool ok =
      equal_area_edge(window.data(), static_cast<int>(window.size()), -window_inner, s_edge, step);
  *s_edge += s_peak;
  return ok;
}

// One sample per point of the side: the edge point in the normalized plane,
// or invalid where no edge is found. kCutByImageBorder when a corner or a
// profile leaves the image.
EdgeFitStatus sample_side(const cv::Mat& gray, const Camera& camera, const SideSampling& side,
                          const DetectorParameters& p, std::vector<double>* profile,
                          std::vector<Sample>* samples) {
  const double margin = p.image_border_margin_px;
  // The corners themselves must lie inside, with the least window an edge
  // needs on either side (windows are cut where the image ends).
  for (const auto& c : {side.n0, side.n1})
    if (!inside_image(gray, distort_normalized(camera, c), margin + p.min_edge_window_px))
      return EdgeFitStatus::kCutByImageBorder;
  samples->assign(side.m, Sample{});
  for (int k = 0; k < side.m; ++k) {
    const Eigen::Vector2d pn = side.point(k);
    const Eigen::Vector2d px = distort_normalized(camera, pn);
    const Eigen::Matrix2d j = distort_jacobian(camera, pn);
    const Eigen::Vector2d tangent = (j * side.dn).normalized();
    const Eigen::Vector2d normal(tangent.y(), -tangent.x());  // outward for a clockwise quad
    double inner = 0, outer = 0;
    if (!edge_window(gray, px, normal, side.half, p, &inner, &outer))
      return EdgeFitStatus::kCutByImageBorder;
    read_profile(gray, px, normal, inner, outer, profile);
    double s_edge = 0, step = 0;
    if (!locate_edge(gray, px, normal, side, inner, p, *profile, &s_edge, &step)) continue;
    // Back to the normalized plane through the local Jacobian.
    const Eigen::Matrix2d j_inv = j.inverse();
    Sample& s = (*samples)[k];
    s.point_norm = pn + j_inv * (s_edge * normal);
    s.jacobian = j;
    s.jac_normal = normal;  // replaced once the line normal is known
    s.step = step;
    s.valid = true;
  }
  return EdgeFitStatus::kOk;
}

// Edge strength: relative to the side's typical step (75th percentile), so
// that an occluded stretch, whose step vanishes, is not an edge. False when
// fewer than three samples found an edge at all.
bool drop_weak_samples(const DetectorParameters& p, std::vector<Sample>* samples) {
  std::vector<double> steps;
  for (const auto& s : *samples)
    if (s.valid) steps.push_back(s.step);
  if (steps.size() < 3) return false;
  const size_t q = steps.size() * 3 / 4;
  std::nth_element(steps.begin(), steps.begin() + q, steps.end());
  const double min_step = std::max(p.min_edge_step, p.min_relative_edge_step * steps[q]);
  for (auto& s : *samples)
    if (s.valid && s.step < min_step) s.valid = false;
  return true;
}

// Robust line: fit, drop samples off the line, refit. The first pass starts
// from the contour polygon, whose corners may be a few pixels off, so that
// samples near a corner can fall beyond the marker: it only needs a line
// through most of the side (residual x 2). False when too few samples remain.
bool fit_robust_line(const SideSampling& side, const DetectorParameters& p,
                     std::vector<Sample>* samples, Line* line) {
  const double max_residual = (side.first_pass ? 2 : 1) * p.max_sample_residual_px;
  for (int round = 0; round < 3; ++round) {
    if (!fit_line(*samples, line)) return false;
    // Image length of a unit step along the line normal, per sample.
    bool changed = false;
    for (int k = 0; k < side.m; ++k) {
      Sample& s = (*samples)[k];
      if (!s.valid) continue;
      s.jac_normal = s.jacobian * line->normal;
      if (std::abs(residual_px(s, *line)) > max_residual) s.valid = false, changed = true;
    }
    if (!changed) break;
  }
  return true;
}

// Support and the longest gap (occlusion, a broken outline). The first pass
// needs half the samples; the occlusion criteria apply to the dense,
// re-centred samples of the later passes.
bool side_supported(const std::vector<Sample>& samples, const SideSampling& side, double length_px,
                    const DetectorParameters& p, int* valid) {
  int gap = 0, longest_gap = 0;
  *valid = 0;
  for (const auto& s : samples) {
    if (s.valid) {
      ++*valid;
      gap = 0;
    } else {
      longest_gap = std::max(longest_gap, ++gap);
    }
  }
  const double min_support = side.first_pass ? 0.5 : p.min_edge_support;
  const double spacing = (side.t1 - side.t0) * length_px / (side.m - 1);
  return !(*valid < min_support * side.m ||
           (!side.first_pass && longest_gap * spacing > p.max_edge_gap_px));
}

SideFit fit_side(const cv::Mat& gray, const Camera& camera, const Eigen::Vector2d& n0,
                 const Eigen::Vector2d& n1, double length_px, bool first_pass,
                 const DetectorParameters& p, std::vector<double>* profile) {
  SideFit out;
  const SideSampling side = plan_side(n0, n1, length_px, first_pass, p);
  std::vector<Sample> samples;
  out.status = sample_side(gray, camera, side, p, profile, &samples);
  if (out.status != EdgeFitStatus::kOk) return out;
  out.status = EdgeFitStatus::kSideNotSupported;
  if (!drop_weak_samples(p, &samples)) return out;
  Line line;
  if (!fit_robust_line(side, p, &samples, &line)) return out;
  int valid = 0;
  if (!side_supported(samples, side, length_px, p, &valid)) return out;
  out.line = line;
  for (const auto& s : samples)
    if (s.valid) out.sum_sq_residual_px += residual_px(s, line) * residual_px(s, line);
  out.inliers = valid;
  out.status = EdgeFitStatus::kOk;
  return out;
}

bool intersect(const Line& a, const Line& b, Eigen::Vector2d* x) {
  Eigen::Matrix2d m;
  m.row(0) = a.normal.transpose();
  m.row(1) = b.normal.transpose();
  const double det = m.determinant();
  if (std::abs(det) < 1e-6) return false;  // sides within 0.06 degrees of parallel
  *x = m.inverse() * Eigen::Vector2d(a.offset, b.offset);
  return x->allFinite();
}

}  // namespace

EdgeFit refine_quad(const cv::Mat& gray, const Camera& camera, const Quad& candidate,
                    const DetectorParameters& p) {
  EdgeFit fit;
  fit.corners_px = candidate;
  for (int i = 0; i < 4; ++i) {
    if (!inside_image(gray, candidate[i], p.image_border_margin_px)) {
      fit.status = EdgeFitStatus::kCutByImageBorder;
      return fit;
    }
    if (!camera.undistort_point(candidate[i], &fit.corners_norm[i])) return fit;
  }
  double shortest = 1e300;
  for (int i = 0; i < 4; ++i)
    shortest = std::min(shortest, (candidate[(i + 1) % 4] - candidate[i]).norm());
  const double max_shift = std::max(2.0, std::min(p.max_corner_shift_px, 0.3 * shortest));

  std::vector<double> profile;
  std::array<Line, 4> lines;
  for (int pass = 0; pass < p.edge_passes; ++pass) {
    double sum_sq = 0;
    int count = 0;
    for (int i = 0; i < 4; ++i) {
      const int next = (i + 1) % 4;
      const double length_px = (fit.corners_px[next] - fit.corners_px[i]).norm();
      const SideFit side = fit_side(gray, camera, fit.corners_norm[i], fit.corners_norm[next],
                                    length_px, pass == 0, p, &profile);
      if (side.status != EdgeFitStatus::kOk) {
        fit.status = side.status;
        return fit;
      }
      lines[i] = side.line;
      sum_sq += side.sum_sq_residual_px;
      count += side.inliers;
    }
    for (int i = 0; i < 4; ++i) {
      Eigen::Vector2d x;
      if (!intersect(lines[(i + 3) % 4], lines[i], &x)) {
        fit.status = EdgeFitStatus::kFitFailed;
        return fit;
      }
      fit.corners_norm[i] = x;
      fit.corners_px[i] = distort_normalized(camera, x);
      if ((fit.corners_px[i] - candidate[i]).norm() > max_shift) {
        fit.status = EdgeFitStatus::kFitFailed;
        return fit;
      }
    }
    fit.residual_px = std::sqrt(sum_sq / std::max(count, 1));
  }
  fit.status =
      fit.residual_px <= p.max_edge_residual_px ? EdgeFitStatus::kOk : EdgeFitStatus::kFitFailed;
  return fit;
}

}  // namespace vision::detail
