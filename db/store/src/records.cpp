#include "db/store/records.hpp"

namespace db::store {

const char* to_string(RunStatus status) {
  switch (status) {
    case RunStatus::kRunning:
      return "running";
    case RunStatus::kCompleted:
      return "completed";
    case RunStatus::kAborted:
      return "aborted";
    case RunStatus::kFailed:
      return "failed";
  }
  return "unknown";
}

const char* to_string(PositionStatus status) {
  return status == PositionStatus::kOk ? "ok" : "failed";
}

bool DetectionRecord::operator==(const DetectionRecord& o) const {
  return detector == o.detector && marker_id == o.marker_id && rotation == o.rotation &&
         corners_px == o.corners_px && contrast == o.contrast &&
         bits_corrected == o.bits_corrected && edge_fit_residual_px == o.edge_fit_residual_px &&
         true_corner_rms_px == o.true_corner_rms_px;
}

bool EstimateRecord::operator==(const EstimateRecord& o) const {
  return solver == o.solver && detector == o.detector && scope == o.scope &&
         R_cam_target == o.R_cam_target && t_cam_target_m == o.t_cam_target_m &&
         distance_m == o.distance_m && reprojection_error_px == o.reprojection_error_px &&
         generalization_error_px == o.generalization_error_px && iterations == o.iterations &&
         converged == o.converged && termination == o.termination && time_us == o.time_us &&
         ambiguity_ratio == o.ambiguity_ratio;
}

bool FrameRecord::operator==(const FrameRecord& o) const {
  return index == o.index && camera_timestamp_ns == o.camera_timestamp_ns &&
         host_timestamp_ns == o.host_timestamp_ns && source == o.source &&
         image_path == o.image_path && image_sha256 == o.image_sha256 &&
         detections == o.detections && estimates == o.estimates;
}

bool PositionRecord::operator==(const PositionRecord& o) const {
  return plan_index == o.plan_index && commanded_x_mm == o.commanded_x_mm &&
         commanded_y_mm == o.commanded_y_mm && measured_x_mm == o.measured_x_mm &&
         measured_y_mm == o.measured_y_mm && true_distance_m == o.true_distance_m &&
         settle_time_s == o.settle_time_s && status == o.status &&
         failure_reason == o.failure_reason && true_viewing_angle_deg == o.true_viewing_angle_deg &&
         true_pose == o.true_pose && distance_bounds == o.distance_bounds &&
         visible_markers == o.visible_markers && stage_times == o.stage_times && frames == o.frames;
}

}  // namespace db::store
