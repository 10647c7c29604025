// rig::sweep::ground_truth_at: what the rig geometry says the camera should see with
// the carriage at a bench position (docs/frames.md): the true pose and
// camera-target distance, the viewing angle, the markers in view with their
// size in pixels, and the Cramér-Rao bound on the distance of any unbiased
// solver, per scope.
//
// Frames and units: T_cam_target as vision::RigGeometry::T_cam_target (metres);
// bench positions in mm; pixels are distorted pixels of `camera`.
#pragma once

#include <vector>

#include "db/store/records.hpp"
#include "vision/camera.hpp"
#include "vision/pose.hpp"
#include "vision/rig_geometry.hpp"
#include "vision/target.hpp"

namespace rig::sweep {

struct GroundTruth {
  vision::Pose T_cam_target;
  double distance_m = 0;  // camera optical centre to the target origin
  // Between the target's normal and the line of sight from the target origin
  // to the camera, degrees (0 = seen head-on).
  double viewing_angle_deg = 0;
  // Markers in view (in front of the camera, the whole distorted outline at
  // least image_border_margin_px + min_edge_window_px of vision's default
  // DetectorParameters, 3 px, inside the image: the white beyond an outer edge
  // that locating it needs), with their mean projected side, px.
  std::vector<db::store::VisibleMarker> visible_markers;
  // Cramér-Rao bound on the distance's standard deviation for 1 px of
  // isotropic corner noise, for the pose marker's scope (its id) when it is in
  // view and for "target" (every marker in view). See vision/cramer_rao.hpp.
  std::vector<db::store::DistanceBound> distance_bounds;
};

// Precondition: x_mm, y_mm finite. Never throws for a pose the camera cannot
// see: the lists are then empty.
GroundTruth ground_truth_at(const vision::RigGeometry& geometry, const vision::Camera& camera,
                            const vision::Target& target, double x_mm, double y_mm);

// The true pose as the database stores it (row-major rotation, metres).
db::store::TruePose stored_true_pose(const vision::Pose& T_cam_target);

}  // namespace rig::sweep
