#pragma once
// Plain values the run database stores and returns. db knows neither vision
// nor motion: rig translates its detections, estimates and bench readings into
// these records (numbers, strings, JSON text), and back for reports.
//
// Frames and units: R_cam_target and t_cam_target_m are the pose of the target
// frame in the camera frame (p_cam = R_cam_target * p_target + t_cam_target_m),
// metres; bench coordinates are millimetres; image coordinates are distorted
// pixels in the OpenCV convention; times are stated per field.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace db::store {

enum class RunStatus { kRunning, kCompleted, kAborted, kFailed };
enum class PositionStatus { kOk, kFailed };

// "running", "completed", "aborted", "failed" (the text stored in runs.status).
const char* to_string(RunStatus status);
// "ok", "failed" (the text stored in positions.status).
const char* to_string(PositionStatus status);

// A file the run depends on, stored as a copy so that a run is
// self-describing after the file has changed or gone. sha256 is filled by
// Store::start_run from content (callers leave it empty).
struct StoredFile {
  std::string path;     // where it was read from, as given (informational)
  std::string content;  // the file's bytes
  std::string sha256;   // 64 lowercase hex characters of SHA-256(content)
};

// What a run is, given when it starts. All JSON fields must hold valid JSON
// (Store::start_run refuses text that does not parse, naming the field).
struct RunDescription {
  std::string config_json;     // the validated sweep configuration, as JSON
  std::string plan_json;       // the plan's positions, as JSON (rig defines the layout)
  std::int64_t plan_size = 0;  // number of positions in the plan, indices 0 .. plan_size-1
  StoredFile sweep_file;
  StoredFile camera_calibration;
  StoredFile target_layout;
  StoredFile rig_geometry;
  StoredFile bench_profile;
  std::string software_version;       // rig's version
  std::string library_versions_json;  // JSON object, e.g. {"opencv":"4.6.0","sqlite":"3.40.1"}
  std::string host;                   // host name of the machine that ran the sweep
  // The detector whose detections stand for the run where one detector's
  // are needed (calibration, frame pictures, external estimators): a
  // registry name of vision/detectors.hpp; "rig" for runs before schema 5.
  std::string primary_detector = "rig";
};

// The camera of a run as it identified itself when the sweep opened it.
// GigE Vision: the GenICam features DeviceVendorName, DeviceModelName,
// DeviceSerialNumber and DeviceVersion; V4L2: the driver as vendor, the card
// as model, the bus as serial and the driver version. "" where the camera
// does not say. The simulated rig's camera reports vendor "rig", model
// "rig-sim" and device version "realism <profile>" (docs/simulated-rig.md).
struct RunCamera {
  std::string source;     // the frame source spec, e.g. "gige:127.0.0.1"
  std::string device_id;  // e.g. "rig-rig-sim-0001" (vendor-model-serial), "" if unknown
  std::string vendor, model, serial, device_version;
};

// A run as stored. Times are UTC, ISO 8601 with milliseconds
// ("2026-11-22T06:18:24.123Z"), set by the store from the system clock.
struct Run {
  std::int64_t id = 0;
  RunDescription description;
  std::string started_at;
  std::optional<std::string> ended_at;  // absent while running
  RunStatus status = RunStatus::kRunning;
  std::string status_reason;        // why it ended that way; empty while running
  std::optional<RunCamera> camera;  // absent: not recorded (runs before schema 3, replays)
};

// Duration of one stage of a position (e.g. "move", "settle", "capture",
// "detect", "solve:ippe", "store"), seconds.
struct StageTime {
  std::string stage;
  double seconds = 0;
  bool operator==(const StageTime& o) const { return stage == o.stage && seconds == o.seconds; }
};

struct DetectionRecord {
  // The detector that found it (a registry name of vision/detectors.hpp).
  std::string detector = "rig";
  int marker_id = -1;
  int rotation = 0;  // quarter turns clockwise of the observed code
  // Corners A, B, C, D as x0, y0, x1, y1, ..., distorted pixels.
  std::array<double, 8> corners_px{};
  double contrast = 0;              // grey levels (8-bit)
  int bits_corrected = 0;           // code bits corrected
  double edge_fit_residual_px = 0;  // RMS of edge samples about the fitted sides, px
  // RMS distance of the corners from the true ones (the layout's corners
  // projected through the run's camera at the true pose), px; absent when
  // the true pose is unknown.
  std::optional<double> true_corner_rms_px;
  bool operator==(const DetectionRecord& o) const;
};

// One solver's result on one frame, for one scope.
struct EstimateRecord {
  std::string solver;  // registry name, e.g. "hybrid_ekf"
  // The detector whose corners it was solved from (vision/detectors.hpp).
  std::string detector = "rig";
  // "target" (all markers of the target) or the marker id as decimal text ("0").
  std::string scope;
  std::array<double, 9> R_cam_target{};           // row-major rotation
  std::array<double, 3> t_cam_target_m{};         // metres
  double distance_m = 0;                          // |t_cam_target|, metres
  double reprojection_error_px = 0;               // RMS, px
  std::optional<double> generalization_error_px;  // paper §3.2; absent for scope "target"
  int iterations = 0;
  bool converged = false;
  std::string termination;                // the solver's termination reason, as text
  double time_us = 0;                     // solve() wall time, microseconds
  std::optional<double> ambiguity_ratio;  // IPPE family only, in [0, 1]
  bool operator==(const EstimateRecord& o) const;
};

struct FrameRecord {
  int index = 0;  // 0 .. frames per position - 1
  // Device timestamp as the camera reports it, nanoseconds; absent if the source has none.
  std::optional<std::int64_t> camera_timestamp_ns;
  std::int64_t host_timestamp_ns = 0;     // host CLOCK_REALTIME at reception, ns since the epoch
  std::string source;                     // frame source description, e.g. "gige:Aravis-Fake-GV01"
  std::optional<std::string> image_path;  // saved raw frame, when frame saving is on
  std::optional<std::string> image_sha256;  // SHA-256 of that file's bytes
  std::vector<DetectionRecord> detections;
  std::vector<EstimateRecord> estimates;
  bool operator==(const FrameRecord& o) const;
};

// The Cramér-Rao bound on the standard deviation of the estimated distance
// at the true pose, for one scope ("target" or a marker id as in
// EstimateRecord::scope), metres per pixel of isotropic corner noise: with
// corner noise sigma px no unbiased solver's distance has a standard deviation
// below sigma * distance_sd_m_per_px.
struct DistanceBound {
  std::string scope;
  double distance_sd_m_per_px = 0;
  bool operator==(const DistanceBound& o) const {
    return scope == o.scope && distance_sd_m_per_px == o.distance_sd_m_per_px;
  }
};

// The true pose of the target frame in the camera frame at a position, from
// the bench read-back and the rig geometry: the truth every solver's
// T_cam_target (EstimateRecord) is compared with. Same frames and units as
// EstimateRecord (row-major rotation, metres).
struct TruePose {
  std::array<double, 9> R_cam_target{};
  std::array<double, 3> t_cam_target_m{};
  bool operator==(const TruePose& o) const {
    return R_cam_target == o.R_cam_target && t_cam_target_m == o.t_cam_target_m;
  }
};

// A marker whose four corners project inside the image at the true pose: the
// detector should have found it. side_px is its mean projected side length.
struct VisibleMarker {
  int marker_id = -1;
  double side_px = 0;
  bool operator==(const VisibleMarker& o) const {
    return marker_id == o.marker_id && side_px == o.side_px;
  }
};

// Something that happened to a run besides its positions: a fault, a pause,
// a resume. Kinds written by rig: "alarm", "link", "camera", "settle"
// (faults of the bench, its link, the camera, the settling), "detect"
// (corners no solver could take), "telemetry" (the socket failed; the sweep
// went on), "pause", "resume", "start" (a replay began). How a run ended is
// its status and reason, not an event.
struct RunEvent {
  std::string at;                          // UTC, ISO 8601 with milliseconds, set by the store
  std::optional<std::int64_t> plan_index;  // the position it happened at, if any
  std::string kind;
  std::string message;
  bool operator==(const RunEvent& o) const {
    return at == o.at && plan_index == o.plan_index && kind == o.kind && message == o.message;
  }
};

// Everything measured at one plan position; Store::append_position writes it
// in one transaction.
struct PositionRecord {
  std::int64_t plan_index = 0;  // index in the run's plan, 0 .. plan_size-1
  double commanded_x_mm = 0, commanded_y_mm = 0;
  // Bench read-back after settling; absent when the bench could not be read.
  std::optional<double> measured_x_mm, measured_y_mm;
  // From the read-back and the rig geometry, metres; absent when unknown.
  std::optional<double> true_distance_m;
  double settle_time_s = 0;  // from move command to settled, seconds
  // Angle between the target's normal and the line of sight from the target
  // origin to the camera at the true pose, degrees; absent when unknown.
  std::optional<double> true_viewing_angle_deg;
  // Absent when unknown, and in runs stored before schema 4.
  std::optional<TruePose> true_pose;
  std::vector<DistanceBound> distance_bounds;  // per scope, at the true pose
  std::vector<VisibleMarker> visible_markers;  // at the true pose, by marker id
  PositionStatus status = PositionStatus::kOk;
  std::string failure_reason;  // empty when status is kOk
  std::vector<StageTime> stage_times;
  std::vector<FrameRecord> frames;
  bool operator==(const PositionRecord& o) const;
};

// One estimate with what a report joins it with.
struct EstimateRow {
  std::int64_t plan_index = 0;
  int frame_index = 0;
  std::optional<double> true_distance_m;
  EstimateRecord estimate;
};

}  // namespace db::store
