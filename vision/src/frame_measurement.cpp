#include "vision/frame_measurement.hpp"

#include <chrono>
#include <cmath>
#include <utility>

#include "vision/codebook.hpp"
#include "vision/correspondences.hpp"
#include "vision/solvers.hpp"
#include "vision/timing.hpp"

namespace vision {
namespace {

using Solvers = std::vector<std::unique_ptr<PoseSolver>>;

// The detected markers of the layout, each id once: an id seen twice in the
// frame is ambiguous and left out.
struct LayoutMarkers {
  const Detection* pose_marker = nullptr;
  std::vector<const Detection*> others;  // in detection order
};

LayoutMarkers layout_markers(const std::vector<Detection>& detections, const Target& target) {
  LayoutMarkers markers;
  for (const auto& d : detections) {
    if (!target.has_marker(d.id)) continue;
    int seen = 0;
    for (const auto& e : detections)
      seen += e.id == d.id;
    if (seen > 1) continue;
    if (d.id == target.pose_marker_id)
      markers.pose_marker = &d;
    else
      markers.others.push_back(&d);
  }
  return markers;
}

// The detected corners A, B, C, D of each marker against their positions on
// the target. Throws InputError (make_correspondences) for a corner outside
// the lens model's invertible region.
Correspondences marker_corners(const Camera& camera, const Target& target,
                               const std::vector<const Detection*>& markers) {
  std::vector<Eigen::Vector3d> object_points;
  std::vector<Eigen::Vector2d> image_points;
  for (const auto* d : markers) {
    const auto corners = target.corners_m(d->id);
    for (int k = 0; k < 4; ++k) {
      object_points.push_back(corners[k]);
      image_points.push_back(d->corners_px[k]);
    }
  }
  return make_correspondences(camera, object_points, image_points);
}

// What the pose marker's poses are checked against (paper §3.2): the other
// markers' detected corners. None when there are no other markers or their
// corners cannot be undistorted.
std::optional<Correspondences> generalization_reference(
    const Camera& camera, const Target& target, const std::vector<const Detection*>& others) {
  if (others.empty()) return std::nullopt;
  try {
    return marker_corners(camera, target, others);
  } catch (const InputError&) {
    return std::nullopt;  // outside the lens model's invertible region
  }
}

// RMS distance, distorted pixels, of the reference corners from their
// projection through T_cam_target; none for a corner on or behind the camera.
std::optional<double> generalization_error_px(const Correspondences& reference,
                                              const Pose& T_cam_target) {
  const double rms = reprojection_rms_px(reference, T_cam_target);
  if (!std::isfinite(rms)) return std::nullopt;
  return rms;
}

// Every solver on the corners of `markers`, appended to m.estimates as scope
// `scope` and timed into m.solve_s; with a reference, each converged pose's
// generalization error. Corners no solver can take go to m.scope_errors.
void solve_scope(const Solvers& solvers, const Camera& camera, const Target& target,
                 const std::string& scope, const std::vector<const Detection*>& markers,
                 const std::optional<Correspondences>& reference, FrameMeasurement& m) {
  Correspondences corners;
  try {
    corners = marker_corners(camera, target, markers);
  } catch (const InputError& e) {
    m.scope_errors.push_back({scope, e.what()});
    return;
  }
  for (const auto& solver : solvers) {
    const auto start = std::chrono::steady_clock::now();
    ScopeEstimate s{scope, solver->solve(corners), std::nullopt};
    m.solve_s[solver->name()] += seconds_since(start);
    if (reference && s.estimate.converged)
      s.generalization_error_px = generalization_error_px(*reference, s.estimate.T_cam_target);
    m.estimates.push_back(std::move(s));
  }
}

}  // namespace

FrameMeasurer::FrameMeasurer(vision::Camera camera, vision::Target target,
                             vision::DetectorParameters parameters)
    : camera_(std::move(camera)),
      target_(std::move(target)),
      detector_(camera_, vision::Codebook(), parameters),
      solvers_(vision::make_all_solvers()) {
  for (const auto& s : solvers_)
    names_.push_back(s->name());
}

FrameMeasurement FrameMeasurer::measure(const cv::Mat& image) const {
  FrameMeasurement m;
  const auto detect_start = std::chrono::steady_clock::now();
  m.detections = detector_.detect(image);
  m.detect_s = seconds_since(detect_start);

  const LayoutMarkers markers = layout_markers(m.detections, target_);
  std::vector<const Detection*> all;
  if (markers.pose_marker) {
    solve_scope(solvers_, camera_, target_, std::to_string(markers.pose_marker->id),
                {markers.pose_marker}, generalization_reference(camera_, target_, markers.others),
                m);
    all.push_back(markers.pose_marker);
  }
  all.insert(all.end(), markers.others.begin(), markers.others.end());
  if (!all.empty()) solve_scope(solvers_, camera_, target_, "target", all, std::nullopt, m);
  return m;
}

}  // namespace vision
