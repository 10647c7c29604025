#include "vision/frame_measurement.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include "vision/codebook.hpp"
#include "vision/correspondences.hpp"
#include "vision/marker_family.hpp"
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
                 const std::optional<Correspondences>& reference, DetectorMeasurement& m) {
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

// The detectors to measure, in registry order, each once; empty: the first
// that reads `family`. Throws DetectorRegistryError (make_detector's) for an
// unknown one or one that cannot decode the family.
std::vector<std::string> measured_detectors(const std::vector<std::string>& wanted,
                                            const std::string& family) {
  if (wanted.empty()) {
    const std::vector<std::string> able = detectors_for_family(family);
    if (able.empty()) {
      throw DetectorRegistryError("marker family \"" + family +
                                  "\": no detector decodes it; expected a family of " +
                                  MarkerFamily::names_text());
    }
    return {able.front()};
  }
  for (const std::string& name : wanted) {
    const auto& known = vision::detector_names();
    if (std::find(known.begin(), known.end(), name) == known.end())
      throw DetectorRegistryError("detector \"" + name + "\": expected one of " +
                                  detector_names_text());
  }
  std::vector<std::string> ordered;
  for (const std::string& name : vision::detector_names())
    if (std::find(wanted.begin(), wanted.end(), name) != wanted.end()) ordered.push_back(name);
  return ordered;
}

DetectorMeasurement measure_with(const FiducialDetector& detector, const Solvers& solvers,
                                 const Camera& camera, const Target& target, const cv::Mat& image) {
  DetectorMeasurement m;
  m.detector = detector.name();
  const auto detect_start = std::chrono::steady_clock::now();
  m.detections = detector.detect(image);
  m.detect_s = seconds_since(detect_start);

  const LayoutMarkers markers = layout_markers(m.detections, target);
  std::vector<const Detection*> all;
  if (markers.pose_marker) {
    solve_scope(solvers, camera, target, std::to_string(markers.pose_marker->id),
                {markers.pose_marker}, generalization_reference(camera, target, markers.others), m);
    all.push_back(markers.pose_marker);
  }
  all.insert(all.end(), markers.others.begin(), markers.others.end());
  if (!all.empty()) solve_scope(solvers, camera, target, "target", all, std::nullopt, m);
  return m;
}

}  // namespace

FrameMeasurer::FrameMeasurer(vision::Camera camera, vision::Target target,
                             vision::DetectorParameters parameters,
                             std::vector<std::string> detectors)
    : camera_(std::move(camera)),
      target_(std::move(target)),
      detector_names_(measured_detectors(detectors, target_.family)),
      solvers_(vision::make_all_solvers()) {
  for (const std::string& name : detector_names_)
    detectors_.push_back(make_detector(name, camera_, target_.family, parameters));
  for (const auto& s : solvers_)
    names_.push_back(s->name());
}

FrameMeasurement FrameMeasurer::measure(const cv::Mat& image) const {
  FrameMeasurement m;
  for (const auto& detector : detectors_)
    m.detectors.push_back(measure_with(*detector, solvers_, camera_, target_, image));
  return m;
}

}  // namespace vision
