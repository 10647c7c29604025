#include "external_estimates.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "vision/correspondences.hpp"
#include "vision/timing.hpp"

namespace rig::sweep {
namespace {

// The detections of layout markers seen once in the frame (an id seen twice
// is ambiguous; vision::FrameMeasurer leaves it out too).
std::map<int, const vision::Detection*> unique_layout_detections(
    const std::vector<vision::Detection>& detections, const vision::Target& target) {
  std::map<int, const vision::Detection*> out;
  std::map<int, int> seen;
  for (const auto& d : detections)
    ++seen[d.id];
  for (const auto& d : detections)
    if (target.has_marker(d.id) && seen[d.id] == 1) out[d.id] = &d;
  return out;
}

// RMS reprojection of `ids`' corners, or NaN when they give no correspondences.
double reprojection_px(const vision::Camera& camera, const vision::Target& target,
                       const std::vector<std::pair<int, std::array<Eigen::Vector2d, 4>>>& corners,
                       const vision::Pose& T) {
  std::vector<Eigen::Vector3d> object;
  std::vector<Eigen::Vector2d> image;
  for (const auto& [id, px] : corners) {
    if (!target.has_marker(id)) continue;
    const auto c = target.corners_m(id);
    for (int k = 0; k < 4; ++k) {
      object.push_back(c[static_cast<std::size_t>(k)]);
      image.push_back(px[static_cast<std::size_t>(k)]);
    }
  }
  try {
    return vision::reprojection_rms_px(vision::make_correspondences(camera, object, image), T);
  } catch (const vision::InputError&) {
    return std::nan("");
  }
}

}  // namespace

db::store::EstimateRecord external_failure_record(const std::string& solver,
                                                  const std::string& termination) {
  db::store::EstimateRecord r;
  r.solver = solver;
  r.scope = "target";
  r.reprojection_error_px = -1;
  r.converged = false;
  r.termination = termination;
  return r;
}

db::store::EstimateRecord external_estimate_record(const std::string& solver,
                                                   const estimator::ExternalPose& pose,
                                                   const vision::Camera& camera,
                                                   const vision::Target& target,
                                                   const std::vector<vision::Detection>& detections,
                                                   double time_us) {
  db::store::EstimateRecord r;
  r.solver = solver;
  r.scope = pose.scope;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j)
      r.R_cam_target[static_cast<std::size_t>(3 * i + j)] = pose.T_cam_target.R(i, j);
    r.t_cam_target_m[static_cast<std::size_t>(i)] = pose.T_cam_target.t(i);
  }
  r.distance_m = pose.T_cam_target.distance_m();
  r.time_us = time_us;
  // rig's corners of the scope's markers; the estimator's when rig has none.
  const auto layout = unique_layout_detections(detections, target);
  std::vector<std::pair<int, std::array<Eigen::Vector2d, 4>>> scope_corners, others;
  for (const auto& [id, d] : layout) {
    const bool in_scope = pose.scope == "target" || pose.scope == std::to_string(id);
    (in_scope ? scope_corners : others).emplace_back(id, d->corners_px);
  }
  if (scope_corners.empty()) scope_corners = pose.corners_px;
  const double rms = reprojection_px(camera, target, scope_corners, pose.T_cam_target);
  r.reprojection_error_px = std::isfinite(rms) ? rms : -1;
  r.converged = std::isfinite(rms);
  r.termination = r.converged             ? "external"
                  : scope_corners.empty() ? "estimator_no_corners"
                                          : "behind_camera";
  if (r.converged && pose.scope != "target" && !others.empty()) {
    const double g = reprojection_px(camera, target, others, pose.T_cam_target);
    if (std::isfinite(g)) r.generalization_error_px = g;
  }
  return r;
}

ExternalEstimates::ExternalEstimates(const std::vector<estimator::EstimatorSpec>& specs,
                                     const vision::Camera& camera, const vision::Target& target)
    : camera_(camera), target_(target) {
  for (const auto& spec : specs)
    estimators_.push_back(std::make_unique<estimator::ExternalEstimator>(spec, camera, target));
}

ExternalEstimates::~ExternalEstimates() {
  for (auto& e : estimators_)
    e->stop();
}

std::vector<std::string> ExternalEstimates::solver_names() const {
  std::vector<std::string> names;
  for (const auto& e : estimators_)
    names.push_back(e->spec().solver_name());
  return names;
}

void ExternalEstimates::log_events(estimator::ExternalEstimator& e,
                                   std::optional<std::int64_t> index, RunLog& log) {
  for (const estimator::LifeEvent& event : e.take_events())
    log.event("estimator", e.spec().solver_name() + ": " + event.message, index);
}

void ExternalEstimates::start(RunLog& log) {
  for (auto& e : estimators_) {
    e->start();
    log_events(*e, std::nullopt, log);
  }
}

void ExternalEstimates::measure(std::int64_t index, const cv::Mat& image,
                                const std::optional<std::string>& saved_png,
                                const vision::FrameMeasurement& m, db::store::FrameRecord& frame,
                                std::map<std::string, double>& solve_s, RunLog& log) {
  if (estimators_.empty()) return;
  const bool any_enabled = std::any_of(estimators_.begin(), estimators_.end(),
                                       [](const auto& e) { return !e->disabled(); });
  estimator::FrameRequest request;
  if (any_enabled) request.image_path = saved_png ? *saved_png : frame_folder_.write(image);
  // The primary detector's corners: rig's, or the first detector that reads
  // the target's family.
  const vision::DetectorMeasurement& primary = m.primary();
  request.detections = &primary.detections;
  for (auto& e : estimators_) {
    const std::string solver = e->spec().solver_name();
    const auto start = std::chrono::steady_clock::now();
    const estimator::FrameResult r = e->estimate(request);
    solve_s[solver] += vision::seconds_since(start);
    log_events(*e, index, log);
    if (r.failure) {
      frame.estimates.push_back(external_failure_record(
          solver, std::string("estimator_") + estimator::to_string(r.failure->kind)));
      frame.estimates.back().detector = primary.detector;
      continue;
    }
    if (r.poses.empty()) {
      frame.estimates.push_back(external_failure_record(solver, "estimator_no_pose"));
      frame.estimates.back().detector = primary.detector;
    }
    for (const auto& pose : r.poses) {
      frame.estimates.push_back(
          external_estimate_record(solver, pose, camera_, target_, primary.detections,
                                   r.estimator_time_us.value_or(r.round_trip_us)));
      frame.estimates.back().detector = primary.detector;
    }
  }
}

}  // namespace rig::sweep
