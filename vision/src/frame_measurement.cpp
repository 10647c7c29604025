#include "vision/frame_measurement.hpp"

#include <chrono>
#include <cmath>
#include <utility>

#include "vision/codebook.hpp"
#include "vision/correspondences.hpp"
#include "vision/solvers.hpp"

namespace vision {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
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
  const auto detect_start = Clock::now();
  m.detections = detector_.detect(image);
  m.detect_s = seconds_since(detect_start);

  // The layout's markers, each id once.
  const vision::Detection* pose_marker = nullptr;
  std::vector<const vision::Detection*> others;
  for (const auto& d : m.detections) {
    if (!target_.has_marker(d.id)) continue;
    int seen = 0;
    for (const auto& e : m.detections)
      seen += e.id == d.id;
    if (seen > 1) continue;
    if (d.id == target_.pose_marker_id)
      pose_marker = &d;
    else
      others.push_back(&d);
  }

  // Generalization error (paper §3.2): the other markers' detected corners
  // against their projection through the pose marker's pose.
  std::optional<vision::Correspondences> other_corners;
  if (!others.empty()) {
    std::vector<Eigen::Vector3d> object_points;
    std::vector<Eigen::Vector2d> image_points;
    for (const auto* d : others) {
      const auto corners = target_.corners_m(d->id);
      for (int k = 0; k < 4; ++k) {
        object_points.push_back(corners[k]);
        image_points.push_back(d->corners_px[k]);
      }
    }
    try {
      other_corners = vision::make_correspondences(camera_, object_points, image_points);
    } catch (const vision::InputError&) {
      // Corners outside the lens model's invertible region: no generalization error.
    }
  }
  auto generalization_error_px = [&](const vision::Pose& T_cam_target) -> std::optional<double> {
    if (!other_corners) return std::nullopt;
    const double rms = vision::reprojection_rms_px(*other_corners, T_cam_target);
    if (!std::isfinite(rms)) return std::nullopt;  // a corner on or behind the camera
    return rms;
  };

  auto solve_scope = [&](const std::string& scope,
                         const std::vector<const vision::Detection*>& markers, bool generalize) {
    std::vector<Eigen::Vector3d> object_points;
    std::vector<Eigen::Vector2d> image_points;
    for (const auto* d : markers) {
      const auto corners = target_.corners_m(d->id);
      for (int k = 0; k < 4; ++k) {
        object_points.push_back(corners[k]);
        image_points.push_back(d->corners_px[k]);
      }
    }
    vision::Correspondences c;
    try {
      c = vision::make_correspondences(camera_, object_points, image_points);
    } catch (const vision::InputError& e) {
      m.scope_errors.push_back({scope, e.what()});
      return;
    }
    for (const auto& solver : solvers_) {
      const auto start = Clock::now();
      ScopeEstimate s{scope, solver->solve(c), std::nullopt};
      m.solve_s[solver->name()] += seconds_since(start);
      if (generalize && s.estimate.converged)
        s.generalization_error_px = generalization_error_px(s.estimate.T_cam_target);
      m.estimates.push_back(std::move(s));
    }
  };

  if (pose_marker) solve_scope(std::to_string(pose_marker->id), {pose_marker}, true);
  std::vector<const vision::Detection*> all;
  if (pose_marker) all.push_back(pose_marker);
  all.insert(all.end(), others.begin(), others.end());
  if (!all.empty()) solve_scope("target", all, false);
  return m;
}

}  // namespace vision
