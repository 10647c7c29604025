#include "rig/sweep/ground_truth.hpp"

#include <cmath>
#include <string>

#include "vision/cramer_rao.hpp"
#include "vision/detector.hpp"
#include "vision/pose_jacobian.hpp"

namespace rig::sweep {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A marker is in view when its whole outline (the black square's edges,
// distorted: barrel distortion bows a side's middle outwards of its corners)
// keeps this far inside [0, width - 1] x [0, height - 1]: the detector locates
// an outer edge only with its white beyond it, and reads that white
// min_edge_window_px beyond the edge and image_border_margin_px from the
// border (vision/detector.hpp). Nearer, the marker is not measurable, only
// seen, and is not counted.
double in_view_margin_px() {
  const vision::DetectorParameters p;
  return p.image_border_margin_px + p.min_edge_window_px;
}

constexpr int kOutlineSamplesPerSide = 16;

// The outline of a marker at `pose` keeps in_view_margin_px() from the border
// and is in front of the camera.
bool outline_in_view(const vision::Camera& camera, const std::array<Eigen::Vector3d, 4>& corners,
                     const vision::Pose& pose) {
  const double m = in_view_margin_px();
  for (int k = 0; k < 4; ++k) {
    for (int s = 0; s < kOutlineSamplesPerSide; ++s) {
      const double f = static_cast<double>(s) / kOutlineSamplesPerSide;
      const Eigen::Vector3d p = pose * ((1 - f) * corners[k] + f * corners[(k + 1) % 4]);
      if (!(p.z() > 0)) return false;
      const Eigen::Vector2d px = camera.project(p);
      if (!(px.x() >= m && px.y() >= m && px.x() <= camera.width_px() - 1 - m &&
            px.y() <= camera.height_px() - 1 - m))
        return false;
    }
  }
  return true;
}

// Corners of the markers projected through `pose`; false if one is behind the camera.
bool project_corners(const vision::Camera& camera, const vision::Target& target,
                     const std::vector<int>& ids, const vision::Pose& pose, Eigen::VectorXd& out) {
  out.resize(8 * static_cast<Eigen::Index>(ids.size()));
  Eigen::Index row = 0;
  for (int id : ids) {
    for (const auto& corner : target.corners_m(id)) {
      const Eigen::Vector3d p = pose.R * corner + pose.t;
      if (!(p.z() > 0)) return false;
      out.segment<2>(row) = camera.project(p);
      row += 2;
    }
  }
  return true;
}

// Bound on sd(distance) for 1 px corner noise: the pose perturbed as
// R' = exp([w]x) R, t' = t + v, the analytic Jacobian of the projected corners
// in (w, v) (vision/pose_jacobian.hpp); d|t|/d(w, v) = (0, t/|t|).
std::optional<double> distance_bound(const vision::Camera& camera, const vision::Target& target,
                                     const std::vector<int>& ids, const vision::Pose& pose) {
  if (ids.empty()) return std::nullopt;
  vision::PoseJacobian J(8 * static_cast<Eigen::Index>(ids.size()), 6);
  Eigen::Index row = 0;
  for (int id : ids) {
    for (const auto& corner : target.corners_m(id)) {
      Eigen::Vector2d px;
      vision::ProjectionJacobian corner_rows;
      if (!vision::project_with_jacobian(camera, pose, corner, &px, &corner_rows))
        return std::nullopt;
      J.middleRows<2>(row) = corner_rows;
      row += 2;
    }
  }
  vision::PoseGradient g = vision::PoseGradient::Zero();
  g.tail<3>() = pose.t / pose.t.norm();
  try {
    return std::sqrt(vision::cramer_rao_bound(vision::cramer_rao_bound(J, 1.0), g));
  } catch (const vision::CramerRaoError&) {
    return std::nullopt;  // e.g. one marker seen edge-on: the pose is not observable
  }
}

}  // namespace

GroundTruth ground_truth_at(const vision::RigGeometry& geometry, const vision::Camera& camera,
                            const vision::Target& target, double x_mm, double y_mm) {
  GroundTruth truth;
  truth.T_cam_target = geometry.T_cam_target(x_mm, y_mm);
  const vision::Pose& T = truth.T_cam_target;
  truth.distance_m = T.t.norm();
  const Eigen::Vector3d normal = T.R.col(2);  // target z, into the sheet, in camera axes
  const double cosine = std::abs(normal.dot(-T.t)) / truth.distance_m;
  truth.viewing_angle_deg = std::acos(std::min(1.0, cosine)) * 180.0 / kPi;

  std::vector<int> in_view;
  for (const auto& marker : target.markers) {
    Eigen::VectorXd px;
    if (!project_corners(camera, target, {marker.id}, T, px)) continue;
    double side = 0;
    for (int k = 0; k < 4; ++k)
      side += (px.segment<2>(2 * k) - px.segment<2>(2 * ((k + 1) % 4))).norm() / 4;
    if (!outline_in_view(camera, target.corners_m(marker.id), T)) continue;
    in_view.push_back(marker.id);
    truth.visible_markers.push_back({marker.id, side});
  }
  for (int id : in_view) {
    if (id != target.pose_marker_id) continue;
    if (auto bound = distance_bound(camera, target, {id}, T))
      truth.distance_bounds.push_back({std::to_string(id), *bound});
  }
  if (auto bound = distance_bound(camera, target, in_view, T))
    truth.distance_bounds.push_back({"target", *bound});
  return truth;
}

db::store::TruePose stored_true_pose(const vision::Pose& T_cam_target) {
  db::store::TruePose pose;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j)
      pose.R_cam_target[3 * i + j] = T_cam_target.R(i, j);
    pose.t_cam_target_m[i] = T_cam_target.t(i);
  }
  return pose;
}

}  // namespace rig::sweep
