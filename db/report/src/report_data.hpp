#pragma once
// The rows of one run that the report's statistics need, read from the run
// database in a few indexed passes (private to db_report).
//
// Query plans (checked by ReportQueries.UseTheIndexesAndScanNoTable in
// tests/db/report/report_input_test.cpp with EXPLAIN QUERY PLAN): the passes
// over frames and detections start from positions (run_id, plan_index) and
// reach frames through (position_id, frame_index) and detections through
// their frame_id index; the estimates are read as one range of row ids,
// found through their frame_id index from the run's frame ids; so no pass
// scans a whole table of a file holding many runs.
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "db/stats/descriptive.hpp"
#include "db/store/records.hpp"

namespace db::report {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

enum class SampleStatus : std::uint8_t { kConverged, kSkipped, kFailed };

// One estimate, without its pose: position is the index into RunData::positions.
struct EstimateSample {
  std::uint32_t position = 0;
  std::uint32_t frame = 0;  // the frame's index at its position
  SampleStatus status = SampleStatus::kConverged;
  double distance_m = kNaN;
  double reprojection_px = kNaN;
  double generalization_px = kNaN;  // NaN: absent
  double time_us = kNaN;
  double ambiguity_ratio = kNaN;  // NaN: absent
  // Against the position's true pose (store::TruePose), converged estimates
  // only, NaN when the truth was not recorded: the translation error
  // t_est - t_true per axis of the camera frame (m) and the rotation error,
  // the angle of R_est^T R_true (degrees, [0, 180]).
  double error_x_m = kNaN, error_y_m = kNaN, error_z_m = kNaN;
  double rotation_error_deg = kNaN;
};

// The estimates of one solver on one scope, in plan index then frame order.
struct SolverScopeData {
  std::string solver, scope;
  std::vector<EstimateSample> samples;
  std::map<std::string, std::size_t> failures_by_termination;
};

// Whether the pose marker's rotation (scope "0") and the whole target's
// (scope "target") of one solver and frame differ, both converged.
struct FlipSample {
  std::uint32_t position = 0;
  double angle_deg = 0;  // rotation angle of R_0^T R_target, degrees
};

// One marker's detections over the frames of one position.
struct MarkerAtPosition {
  int marker_id = -1;
  std::size_t frames_detected = 0;
  std::size_t corner_dof = 0;     // sum over the 8 coordinates of (n - 1)
  double corner_sum_squares = 0;  // sum of squared deviations from each coordinate's mean, px^2
  stats::Summary edge_fit_residual_px;  // over the frames that detected it
  double side_px = 0;                   // mean side length of the detected quadrilateral, px
};

struct PositionData {
  store::PositionRecord record;  // without frames
  std::size_t frames = 0;
  std::vector<MarkerAtPosition> markers;  // detected markers, by id
};

// What the detections of one detector add up to over a run.
struct DetectorData {
  std::string detector;
  std::size_t views_found = 0;        // markers in view found, each once per frame
  std::size_t corners_vs_truth = 0;   // of those, detections with a true-corner RMS
  double corner_sum_squares_px2 = 0;  // sum of their squared true-corner RMS, px^2
  std::size_t misplaced = 0;          // detections of markers in view > 10 px from their truth
};

struct RunData {
  std::string database;
  store::Run run;
  std::vector<PositionData> positions;                   // by plan index
  std::vector<SolverScopeData> solvers;                  // sorted by solver, scope
  std::map<std::string, std::vector<FlipSample>> flips;  // by solver
  std::vector<store::RunEvent> events;
  // Detections with a non-finite corner coordinate or edge-fit residual: a
  // detector bug, left out of every detection figure (as if not detected)
  // and counted here rather than poisoning the corner noise.
  std::size_t nonfinite_detections = 0;
  std::vector<DetectorData> detectors;  // the primary detector first, then by name
};

// Opens `database` read-only and picks the run (run_id or the latest
// completed one). Throws ReportInputError for unusable input, StoreError for
// a failure while reading. `amend_truth`, when set, is called once with the
// run and its positions before the estimates are read, so that every error
// (distance and pose) is taken against the truth it leaves.
// `estimate_readers`: 2 reads the estimates in two parts on two threads and
// connections, 1 in one part on this thread; both give the same RunData.
RunData load_run(const std::string& database, std::optional<std::int64_t> run_id,
                 const std::function<void(RunData&)>& amend_truth = {}, int estimate_readers = 2);

// The SQL of the passes over estimates and detections (for the plan test).
extern const char* const kEstimateIdsQuery;
extern const char* const kEstimatesQuery;
extern const char* const kDetectionsQuery;
extern const char* const kFramesQuery;

}  // namespace db::report
