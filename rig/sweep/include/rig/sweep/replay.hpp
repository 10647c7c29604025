// Replay of a recorded sweep: `rig sweep SWEEP.toml --replay RUN`
// measures the raw frames a run saved (sweep file `[capture] save_frames`)
// again, with the solvers, calibration, target layout and rig geometry of
// today, into a new run.
//
// The controller knows the bench and the camera only through motion::Bench and
// vision::FrameSource, so a replay is a bench and a frame source backed by the
// recorded run:
//
//   RecordedRun   what the run stored per plan position: commanded and
//                 measured XY, status, and the saved frames' paths and SHA-256
//   ReplayCursor  which recorded position the replay "bench" stands at
//   ReplayBench   move_to(x, y) selects the plan position with that commanded
//                 XY; wait_settled() reports the recorded read-back there
//   ReplayFrames  serves the selected position's saved frames, in order, each
//                 checked against its stored SHA-256
//
// Positions the recorded run did not measure fully fail again in the replay,
// with a reason naming the recorded run: no read-back (it failed to settle, or
// it was never measured) -> motion::BenchTimeout from wait_settled, which the
// controller stores as a failed "settle" position; a read-back but no frames
// (it failed at the camera) or a frame file that is missing or changed ->
// vision::CaptureError from grab, stored as a failed "camera" position.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "db/store/records.hpp"
#include "db/store/store.hpp"
#include "motion/bench.hpp"
#include "rig/sweep/run_record.hpp"
#include "rig/sweep/sweep_config.hpp"
#include "rig/sweep/sweep_plan.hpp"
#include "vision/frame_source.hpp"

namespace rig::sweep {

// One saved raw frame of a recorded position.
struct RecordedFrame {
  int index = 0;             // frame index at its position, 0 .. N-1
  std::string image_path;    // absolute path of the PNG, as the run stored it
  std::string image_sha256;  // SHA-256 of the file's bytes, 64 lowercase hex
};

// One plan position of a recorded run, stored or not.
struct RecordedPosition {
  std::int64_t plan_index = 0;
  double commanded_x_mm = 0, commanded_y_mm = 0;  // from the run's plan
  bool stored = false;                            // the run has this position
  // Bench read-back after settling, mm; absent when not stored or when the
  // position failed before the bench settled.
  std::optional<double> measured_x_mm, measured_y_mm;
  db::store::PositionStatus status = db::store::PositionStatus::kFailed;  // kFailed when not stored
  std::string failure_reason;  // as stored; empty when ok
  // The frames the run saved, by frame index; empty when the position failed
  // or frames were not saved.
  std::vector<RecordedFrame> frames;
};

// A run of a database with its plan and what it stored at every plan
// position. Immutable once loaded.
class RecordedRun {
 public:
  // Reads run `run_id` of `store`: its plan (runs.plan_json) and every stored
  // position with its frames' paths and hashes. Reads every position in full
  // (frames with detections and estimates), about a second for the paper's
  // 1,939 positions. Throws db::store::StoreError for an unknown run, PlanError for
  // a plan that does not parse.
  static RecordedRun load(const db::store::Store& store, std::int64_t run_id);

  std::int64_t run_id() const { return run_.id; }
  // The database file it was read from, as the Store names it.
  const std::string& database() const { return database_; }
  const db::store::Run& run() const { return run_; }
  const SweepPlan& plan() const { return plan_; }
  // One per plan position, in plan order (positions()[i].plan_index == i).
  const std::vector<RecordedPosition>& positions() const { return positions_; }

  // The smallest number of saved frames of an ok position that has any; 0
  // when the run saved no frames. A replay can take at most this many frames
  // per position.
  int saved_frames_per_position() const;
  // The run `replay_of` in its configuration, when this run is itself a
  // replay: {"database": ..., "run": ...}; null otherwise.
  nlohmann::json replay_of() const;

  // "run 7 of /abs/run.db", for messages.
  std::string describe() const;
  // Why position `plan_index` has no read-back or no frames, for messages:
  // "it failed: camera: ..." or "it was never measured (run 7 ended aborted:
  // SIGINT received ...)".
  std::string why_missing(std::int64_t plan_index) const;

 private:
  RecordedRun() = default;
  std::string database_;
  db::store::Run run_;
  SweepPlan plan_;
  std::vector<RecordedPosition> positions_;
};

// Which recorded position the replay bench stands at, shared by ReplayBench
// (which moves it) and ReplayFrames (which serves its frames). Single-threaded,
// like the controller that drives both.
class ReplayCursor {
 public:
  // Precondition: run is not null.
  explicit ReplayCursor(std::shared_ptr<const RecordedRun> run);

  const RecordedRun& run() const { return *run_; }

  // Selects the plan position with commanded XY (x_mm, y_mm), equal within
  // kXyMatchMm: the first such position in plan order that the replay has not
  // yet settled at, else (a plan that revisits a point more often than the
  // controller moves there) the first such position. Plans store commanded XY
  // exactly (SweepPlan::to_json round-trips doubles), so the tolerance only
  // absorbs a position recomputed by other arithmetic. Resets the frame
  // counter. Throws motion::SoftLimitError naming the XY and the run when no
  // plan position has that XY or a value is not finite.
  void select(double x_mm, double y_mm);
  static constexpr double kXyMatchMm = 1e-6;

  // The selected position; nullptr before the first select().
  const RecordedPosition* selected() const;
  // Marks the selected position as settled at (see select()).
  void mark_settled();
  // Index of the next frame grab() serves at the selected position, and
  // advancing it.
  int next_frame() const { return next_frame_; }
  void advance_frame() { ++next_frame_; }

 private:
  std::shared_ptr<const RecordedRun> run_;
  std::optional<std::size_t> selected_;
  std::vector<bool> settled_;
  int next_frame_ = 0;
};

// motion::Bench over a recorded run: it never moves anything. home(), stop()
// and reset_alarm() do nothing; status() is always homed, in position, without
// alarm.
class ReplayBench : public motion::Bench {
 public:
  explicit ReplayBench(std::shared_ptr<ReplayCursor> cursor);

  void home() override {}
  // Selects the recorded position commanded at (x_mm, y_mm) (ReplayCursor::select).
  // Throws motion::SoftLimitError when the recorded plan has no such position.
  void move_to(double x_mm, double y_mm) override;
  // Returns at once with the recorded read-back of the selected position as
  // the position. Throws motion::BenchTimeout naming the position and the run
  // when the run has no read-back there (it failed before settling, or never
  // measured it). `timeout` is not used.
  motion::BenchStatus wait_settled(std::chrono::milliseconds timeout) override;
  // The last recorded read-back reported by wait_settled (0, 0 before any).
  motion::XY position() override;
  motion::BenchStatus status() override;
  void stop() override {}
  void reset_alarm() override {}

 private:
  std::shared_ptr<ReplayCursor> cursor_;
  motion::XY position_;
};

// vision::FrameSource over a recorded run: the saved frames of the position
// the ReplayBench selected, in frame order.
//
// Each frame's host_time is the time of the grab, not of the recording: the
// controller only accepts frames exposed after the bench settled, and the
// replay "settles" just before. camera_timestamp_ns is 0 (no device); origin
// is the PNG's path, which the new run stores as the frame's source.
class ReplayFrames : public vision::FrameSource {
 public:
  explicit ReplayFrames(std::shared_ptr<ReplayCursor> cursor);

  void open() override { open_ = true; }
  // Nothing to expose: the frames exist.
  void trigger() override {}
  // Reads the selected position's next frame: the file's bytes, their SHA-256
  // checked against the stored one, then decoded unchanged (Mono8 -> CV_8UC1,
  // Mono16 -> CV_16UC1). Throws vision::CaptureError (device: name()) naming
  // the position and the file when the position has no saved frames (with
  // why: RecordedRun::why_missing), the file is missing or unreadable, its
  // SHA-256 differs from the stored one, or it does not decode; EndOfFrames
  // when the position's saved frames are used up. `timeout` is not used.
  vision::Frame grab(std::chrono::milliseconds timeout) override;
  void close() override { open_ = false; }

  // "replay of run 7 of /abs/run.db"
  std::string name() const override;
  vision::CaptureCounters counters() const override { return counters_; }

 private:
  std::shared_ptr<ReplayCursor> cursor_;
  bool open_ = false;
  vision::CaptureCounters counters_;
};

// The sweep configuration a replay of `recorded` runs with: `config` with
// frame saving off (the frames are on disk already; the new run's frames name
// their PNG as source) and max_consecutive_failed above the plan's size (the
// failures a replay meets are the recorded run's, not a camera that fell off:
// every plan position is visited once). Checks, throwing RunMismatch with the
// input, the value and what was expected:
//   - the run saved frames: "run 7 of DB saved no frames (set [capture]
//     save_frames in the sweep file)" (for a replay run, naming its original);
//   - capture.frames_per_position <= RecordedRun::saved_frames_per_position();
//   - the first saved frame that reads and verifies has the calibration's
//     image size ("capture.calibration: ... is for 640x480 px but frame PATH
//     of run 7 of DB is 736x571 px ...", vision::Camera::image_size_mismatch).
SweepConfig replay_config(const SweepConfig& config, const RecordedRun& recorded);

}  // namespace rig::sweep
