// What rig stores of a frame: the measurer's detections and estimates as the
// run database's records (db knows neither vision nor rig).
#include <cmath>

#include "rig/sweep/controller.hpp"

namespace rig::sweep {
namespace {

// RMS distance, px, of a detection's corners from the layout's corners
// projected through `camera` at the true pose; none for a marker not in the
// layout or a corner behind the camera.
std::optional<double> true_corner_rms_px(const vision::Detection& d, const TrueCorners& truth) {
  if (!truth.target.has_marker(d.id)) return std::nullopt;
  const auto corners_m = truth.target.corners_m(d.id);
  double sum_sq = 0;
  for (std::size_t k = 0; k < 4; ++k) {
    const Eigen::Vector3d p_cam = truth.T_cam_target.R * corners_m[k] + truth.T_cam_target.t;
    if (!(p_cam.z() > 0)) return std::nullopt;
    sum_sq += (truth.camera.project(p_cam) - d.corners_px[k]).squaredNorm();
  }
  const double rms = std::sqrt(sum_sq / 4);
  if (!std::isfinite(rms)) return std::nullopt;
  return rms;
}

db::store::DetectionRecord to_record(const std::string& detector, const vision::Detection& d,
                                     const std::optional<TrueCorners>& truth) {
  db::store::DetectionRecord r;
  r.detector = detector;
  if (truth) r.true_corner_rms_px = true_corner_rms_px(d, *truth);
  r.marker_id = d.id;
  r.rotation = d.rotation;
  for (int k = 0; k < 4; ++k) {
    r.corners_px[2 * k] = d.corners_px[k].x();
    r.corners_px[2 * k + 1] = d.corners_px[k].y();
  }
  r.contrast = d.quality.contrast;
  r.bits_corrected = d.quality.bits_corrected;
  r.edge_fit_residual_px = d.quality.edge_fit_residual_px;
  return r;
}

db::store::EstimateRecord to_record(const std::string& detector, const vision::ScopeEstimate& s) {
  const vision::Estimate& e = s.estimate;
  db::store::EstimateRecord r;
  r.solver = e.solver;
  r.detector = detector;
  r.scope = s.scope;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j)
      r.R_cam_target[3 * i + j] = e.T_cam_target.R(i, j);
    r.t_cam_target_m[i] = e.T_cam_target.t(i);
  }
  // A solver that did not apply or failed numerically may leave NaN in the
  // pose; the database keeps numbers, and `converged` says whether to use them.
  for (double& v : r.R_cam_target)
    if (!std::isfinite(v)) v = 0;
  for (double& v : r.t_cam_target_m)
    if (!std::isfinite(v)) v = 0;
  r.distance_m = std::isfinite(e.distance_m) ? e.distance_m : 0;
  r.reprojection_error_px = std::isfinite(e.reprojection_error_px) ? e.reprojection_error_px : -1;
  r.generalization_error_px = s.generalization_error_px;
  r.iterations = e.iterations;
  r.converged = e.converged;
  r.termination = e.applicable() ? vision::to_string(e.termination) : "skipped";
  r.time_us = e.time_us;
  r.ambiguity_ratio = e.ambiguity_ratio;
  return r;
}

}  // namespace

db::store::FrameRecord to_frame_record(const vision::FrameMeasurement& m, int frame_index,
                                       const std::optional<TrueCorners>& truth) {
  db::store::FrameRecord f;
  f.index = frame_index;
  for (const vision::DetectorMeasurement& dm : m.detectors) {
    for (const auto& d : dm.detections)
      f.detections.push_back(to_record(dm.detector, d, truth));
    for (const auto& e : dm.estimates)
      f.estimates.push_back(to_record(dm.detector, e));
  }
  return f;
}

}  // namespace rig::sweep
