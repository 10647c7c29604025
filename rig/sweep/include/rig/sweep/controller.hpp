// rig::sweep::Controller: the sweep (docs/data-flow.md). For each plan position the run
// does not have yet, in plan order: move, wait_settled, trigger and grab N
// frames, detect, run every solver on the pose marker and on the whole
// target, compute the truth from the bench's READ-BACK position and the rig
// geometry, store the position in one transaction, publish it.
//
// Frames are measured in parallel (the sweep file's [compute] threads,
// rig::sweep::FramePool): each frame goes to the pool as it is grabbed, so
// the frames of a position are measured while the next ones are exposed and
// while each other is measured; the measurements are taken in frame order on
// the controller's thread, which alone logs, publishes, runs the external
// estimators and stores. With SweepConfig::acquire_ahead (a replay) the next
// position is acquired (moved to, settled, its frames grabbed) before the
// current one is finished and stored. Either way the rows stored, the events
// and the telemetry are those of the serial path, in the same order.
//
// The controller knows the bench and the camera only through motion::Bench
// and vision::FrameSource, the database only through db::store::Store.
//
// Faults (the policy is the sweep file's [faults]):
//   bench alarm or emergency stop   stop the bench, record, then pause (until
//                                   `rig ctl resume`, which resets the alarm
//                                   and retries the position) or abort
//   bench link lost                 the driver reconnects by itself; if it
//                                   gives up, retry the position up to
//                                   link_retries times, then the run fails
//   camera lost (a grab or trigger  the camera is closed and opened again
//   fails after its own retries)    until it delivers a frame, within
//                                   faults.camera_reopen_timeout; then the
//                                   frames are taken again (once)
//   settle timeout, camera not      the position is stored as failed with its
//   back in time, incomplete        reason and the sweep continues; after
//   frames, bench moved during      max_consecutive_failed of them, abort
//   the exposure
//   abort requested (rig ctl abort, the current position is finished and
//   SIGINT/SIGTERM via ControlState) stored, then the run ends aborted
// Whatever happens, every stored position is whole (db::store::Store) and the run can
// be resumed from its first missing position (`rig sweep --resume`).
//
// A frame is only taken after wait_settled: a frame the source delivered
// with a host time before the bench was settled is discarded (a free-running
// source), and the read-back is checked again after the last frame; if the
// bench moved by more than the profile's position tolerance meanwhile, the
// frames are rejected and taken again (up to capture.retries times).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "db/store/store.hpp"
#include "motion/bench.hpp"
#include "rig/sweep/sweep_config.hpp"
#include "rig/telemetry/telemetry.hpp"
#include "vision/frame_measurement.hpp"
#include "vision/frame_source.hpp"
#include "vision/pose.hpp"

namespace rig::sweep {

// How a run ended, as stored.
struct RunOutcome {
  db::store::RunStatus status = db::store::RunStatus::kCompleted;
  std::string reason;             // empty when completed
  std::int64_t positions_ok = 0;  // stored in this session
  std::int64_t positions_failed = 0;
  std::int64_t stored_total = 0;  // positions the run has now (all sessions)
};

class Controller {
 public:
  // plan: the run's plan (for a resumed run, the stored one). The run must
  // exist in `store` and be running. telemetry may be null. Every argument is
  // kept by reference and must outlive the Controller.
  Controller(const SweepConfig& config, const SweepPlan& plan, motion::Bench& bench,
             vision::FrameSource& camera, db::store::Store& store, std::int64_t run_id,
             telemetry::ControlState& control, telemetry::TelemetryPublisher* telemetry);
  ~Controller();

  // Measures every position the run does not have, then finishes the run in
  // the store (completed, aborted or failed with a reason) and publishes
  // run_stop. Returns how it ended. Exceptions other than the faults above
  // (a database that cannot be written) finish the run as failed when the
  // database allows it, then propagate.
  RunOutcome run();

  // Positions the run has stored as failed are measured again too, in plan
  // order with the missing ones, each replacing its failed record
  // (db::store::Store::retake_failed_position) after a "retake" event that
  // keeps the reason it failed. For `rig sweep --resume RUN --retry-failed`.
  // Call before run().
  void retake_failed_positions();

  // Also hands every telemetry message to `observer` (on the controller's
  // thread), e.g. for the progress bar of `rig sweep`. Call before run().
  void set_observer(std::function<void(const nlohmann::json&)> observer);

  // Thread-safe snapshot for the control socket's `status`:
  // {"state", "run_id", "completed", "plan_size", "current_index", "eta_s"}.
  nlohmann::json status() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// What the true corners of a frame are computed from: the layout's corners
// (metres, target frame) projected through `camera` at T_cam_target (the
// truth from the bench read-back and the rig geometry).
struct TrueCorners {
  const vision::Camera& camera;
  const vision::Target& target;
  vision::Pose T_cam_target;
};

// What rig stores per frame, from what the measurer found: every detector's
// detections and estimates, each record naming its detector, the primary
// detector's first. With `truth`, each detection of a layout marker gets its
// RMS distance from its true corners (DetectionRecord::true_corner_rms_px).
db::store::FrameRecord to_frame_record(const vision::FrameMeasurement& measurement, int frame_index,
                                       const std::optional<TrueCorners>& truth = std::nullopt);

}  // namespace rig::sweep
