#include "rig/sweep/controller.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <thread>
#include <utility>
#include <vector>

#include "db/store/sha256.hpp"
#include "external_estimates.hpp"
#include "motion/errors.hpp"
#include "rig/sweep/frame_files.hpp"
#include "rig/sweep/frame_pool.hpp"
#include "rig/sweep/ground_truth.hpp"
#include "rig/sweep/sweep_camera.hpp"
#include "run_log.hpp"
#include "vision/image_codecs.hpp"
#include "vision/timing.hpp"

namespace rig::sweep {
namespace {

using Clock = std::chrono::steady_clock;

std::int64_t ns_since_epoch(std::chrono::system_clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

// The run cannot go on: it ends with this status and reason.
struct RunEnd {
  db::store::RunStatus status;
  std::string reason;
};

// The position cannot be measured: it is stored as failed with this reason.
struct PositionFailure {
  std::string kind;  // event kind: "camera", "settle", ...
  std::string reason;
};

// Fault handling under the sweep file's [faults] policy (controller.hpp):
// pauses, requested or after a bench alarm; aborts; alarms; link drops.
class FaultHandler {
 public:
  FaultHandler(const FaultPolicy& policy, motion::Bench& bench, telemetry::ControlState& control,
               RunLog& log)
      : policy_(policy), bench_(bench), control_(control), log_(log) {}

  // Waits out a pause (requested, or after an alarm). Returns false when the
  // run is to be aborted.
  bool honour_pause(std::optional<std::int64_t> index) {
    if (control_.abort_requested()) return false;
    if (!control_.pause_requested()) return true;
    log_.event("pause",
               control_.paused_by_controller() ? "paused after a fault" : "pause requested", index);
    log_.set_state("paused");
    const auto pause_start = Clock::now();
    const bool go_on = control_.wait_while_paused();
    log_.add_paused(vision::seconds_since(pause_start));
    if (!go_on) return false;
    log_.event("resume", "resumed", index);
    log_.set_state("running");
    return true;
  }

  // The abort's reason (or "aborted") and where it happened.
  std::string abort_reason(const std::string& context) const {
    const std::string reason = control_.abort_reason();
    return (reason.empty() ? std::string("aborted") : reason) + " (" + context + ")";
  }

  // A bench alarm or emergency stop while moving to position `index`: the
  // bench is stopped and the alarm recorded; then the run is aborted (throws
  // RunEnd) or pauses until resumed, when the alarm is reset and the move is
  // to be retried (returns).
  void on_alarm(const motion::BenchFault& e, std::int64_t index) {
    try {
      bench_.stop();
    } catch (const motion::BenchError&) {
      // The alarm is what we report; a failing stop adds nothing.
    }
    if (policy_.on_alarm == AlarmAction::kAbort) {
      log_.fault("alarm", e.what(), "abort", index);
      throw RunEnd{db::store::RunStatus::kAborted, std::string("bench alarm: ") + e.what()};
    }
    log_.fault("alarm", e.what(), "pause", index);
    control_.set_paused_by_controller(true);
    if (!honour_pause(index))
      throw RunEnd{db::store::RunStatus::kAborted, abort_reason("after a bench alarm")};
    try {
      bench_.reset_alarm();
    } catch (const motion::BenchFault& again) {
      log_.fault("alarm", std::string("alarm persists after reset: ") + again.what(), "pause",
                 index);
      control_.set_paused_by_controller(true);
    } catch (const motion::BenchLinkError& link) {
      // The move is retried next; a link that stays down ends there.
      log_.fault("link", std::string("resetting the alarm: ") + link.what(), "retry", index);
    }
  }

  // The bench link is down (the driver gave up reconnecting) for the
  // `failures`-th time at position `index`: the move is to be retried
  // (returns) up to link_retries times, then the run fails (throws RunEnd).
  void on_link_lost(const motion::BenchLinkError& e, std::int64_t index, int failures) {
    if (failures > policy_.link_retries) {
      log_.fault("link", e.what(), "abort", index);
      throw RunEnd{db::store::RunStatus::kFailed,
                   "bench link lost after " + std::to_string(failures) + " attempts: " + e.what()};
    }
    log_.fault("link", e.what(), "retry", index);
  }

 private:
  const FaultPolicy& policy_;
  motion::Bench& bench_;
  telemetry::ControlState& control_;
  RunLog& log_;
};

// A frame as grabbed, and its measurement under way in the FramePool.
struct CapturedFrame {
  vision::Frame frame;
  FramePool::Ticket measurement;
};

// What one plan position measures (controller.hpp): the move and settle, the
// frames after it, the truth at the read-back, every solver on every frame,
// the frames saved when the sweep file asks for it.
class PositionMeasurer {
 public:
  PositionMeasurer(const SweepConfig& config, const SweepPlan& plan, motion::Bench& bench,
                   vision::FrameSource& camera, RunLog& log, FaultHandler& faults,
                   std::optional<std::filesystem::path> frames_folder)
      : config_(config),
        plan_(plan),
        bench_(bench),
        camera_(camera),
        log_(log),
        faults_(faults),
        measurer_(config.camera, config.target, {}, config.detectors),
        pool_(measurer_, config.compute_threads),
        externals_(config.estimators, measurer_.camera(), measurer_.target()),
        frames_folder_(std::move(frames_folder)) {}

  // The built-in solvers, then the external estimators ("ext:NAME").
  std::vector<std::string> solver_names() const {
    std::vector<std::string> names = measurer_.solver_names();
    for (const std::string& name : externals_.solver_names())
      names.push_back(name);
    return names;
  }

  // Before the first move: the folder the frames go to exists and takes new
  // files, or the run ends failed here.
  // The external estimators are started here too (a failed start is
  // recorded and contained like any estimator failure).
  void prepare() {
    externals_.start(log_);
    if (!frames_folder_) return;
    try {
      prepare_frames_folder(*frames_folder_);
    } catch (const std::runtime_error& e) {
      throw RunEnd{db::store::RunStatus::kFailed, std::string("capture.save_frames: ") + e.what()};
    }
  }

  // The record of position `index`: ok, or failed with its reason (the fault
  // recorded). Throws RunEnd when the run cannot go on.
  db::store::PositionRecord measure(std::int64_t index) { return finish(acquire(index)); }

  // A position acquired: moved, settled, its frames taken and being measured
  // in the FramePool; or why it failed, not yet recorded.
  struct Acquired {
    db::store::PositionRecord rec;
    std::vector<CapturedFrame> frames;
    std::optional<PositionFailure> failure;
  };

  // The first half of measure(): the move, the settle and the frames. The
  // faults the position survives are recorded as they happen; the one that
  // fails it is kept for finish(). Throws RunEnd when the run cannot go on.
  Acquired acquire(std::int64_t index) {
    const PlanPosition& p = plan_.positions()[static_cast<std::size_t>(index)];
    Acquired a;
    a.rec.plan_index = index;
    a.rec.commanded_x_mm = p.x_mm;
    a.rec.commanded_y_mm = p.y_mm;
    try {
      a.frames = settle_and_capture(index, p, a.rec);
    } catch (const PositionFailure& f) {
      a.failure = f;
    }
    return a;
  }

  // The second half of measure(): the failure recorded, or the truth and the
  // frames' measurements (external estimators included). Throws RunEnd when
  // the run cannot go on.
  db::store::PositionRecord finish(Acquired a) {
    db::store::PositionRecord& rec = a.rec;
    if (a.failure) {
      log_.fault(a.failure->kind, a.failure->reason, "position_failed", rec.plan_index);
      rec.status = db::store::PositionStatus::kFailed;
      rec.failure_reason = a.failure->kind + ": " + a.failure->reason;
      rec.frames.clear();
      return std::move(rec);
    }
    const vision::Pose truth = add_truth(rec);
    measure_frames(rec.plan_index, a.frames, truth, rec);
    rec.status = db::store::PositionStatus::kOk;
    return std::move(rec);
  }

 private:
  // Moves to the position and waits until settled; alarms and link drops go
  // to the fault handler, which retries, pauses or ends the run. Returns the
  // settled status and the settle time.
  std::pair<motion::BenchStatus, double> move_and_settle(std::int64_t index, const PlanPosition& p,
                                                         db::store::PositionRecord& rec) {
    int link_failures = 0, rehomed = 0;
    for (;;) {
      try {
        const auto move_start = Clock::now();
        bench_.move_to(p.x_mm, p.y_mm);
        const double move_s = vision::seconds_since(move_start);
        const auto settle_start = Clock::now();
        const motion::BenchStatus status = bench_.wait_settled(config_.settle.timeout);
        const double settle_s = vision::seconds_since(settle_start);
        rec.stage_times.push_back({"move", move_s});
        rec.stage_times.push_back({"settle", settle_s});
        return {status, move_s + settle_s};
      } catch (const motion::BenchFault& e) {
        // At most one homing per link failure: a drive that raises "not
        // homed" right after being homed is an alarm like any other.
        if (rehomed > link_failures || !home_again_if_lost(index))
          faults_.on_alarm(e, index);
        else
          ++rehomed;
      } catch (const motion::BenchLinkError& e) {
        faults_.on_link_lost(e, index, ++link_failures);
        if (home_again_if_lost(index)) ++rehomed;
      } catch (const motion::BenchTimeout& e) {
        throw PositionFailure{"settle", e.what()};
      } catch (const motion::SoftLimitError& e) {
        // load_sweep_config checked every position against the same limits.
        throw RunEnd{db::store::RunStatus::kFailed, e.what()};
      }
    }
  }

  // A drive that restarted (seen as a link drop, or as "not homed" on the
  // next move when the drop happened between two bench commands) has lost
  // its homing, and a move would only raise "not homed" again. With
  // home_first it is homed again (its alarm reset first) and the move is
  // retried: returns true. Returns false when the bench is homed (nothing to
  // do) or the link is still down (the retry meets it and counts it).
  // Without home_first the run fails saying so.
  bool home_again_if_lost(std::int64_t index) {
    try {
      const motion::BenchStatus status = bench_.status();
      if (status.homed) return false;
      if (!config_.home_first)
        throw RunEnd{db::store::RunStatus::kFailed,
                     "the bench lost its homing (the drive restarted) and home_first = false: "
                     "home it, then resume the run"};
      log_.event("home", "the bench lost its homing (the drive restarted): homing again", index);
      if (status.alarm) bench_.reset_alarm();
      bench_.home();
      bench_.wait_settled(std::chrono::milliseconds(config_.bench_profile.timing.home_timeout_ms));
      return true;
    } catch (const motion::BenchLinkError&) {
      return false;
    } catch (const motion::BenchFault& e) {
      faults_.on_alarm(e, index);  // pauses or aborts per [faults] on_alarm
      return false;
    } catch (const motion::BenchTimeout& e) {
      throw RunEnd{db::store::RunStatus::kFailed,
                   std::string("homing again after the drive restarted: ") + e.what()};
    }
  }

  // Moves, settles and takes the position's frames, each handed to the
  // FramePool as it arrives; takes them again when the read-back moved
  // during the exposures (capture_retries times, then the position fails;
  // the measurements of frames taken again are dropped). Fills the record's
  // read-back and stage times.
  std::vector<CapturedFrame> settle_and_capture(std::int64_t index, const PlanPosition& p,
                                                db::store::PositionRecord& rec) {
    for (int attempt = 0;; ++attempt) {
      const auto [status, settle_s] = move_and_settle(index, p, rec);
      rec.settle_time_s = settle_s;
      rec.measured_x_mm = status.position.x_mm;
      rec.measured_y_mm = status.position.y_mm;
      const auto settled_at = std::chrono::system_clock::now();
      if (config_.settle.dwell.count() > 0) std::this_thread::sleep_for(config_.settle.dwell);
      const auto capture_start = Clock::now();
      std::vector<CapturedFrame> frames = capture_reopening(index, settled_at);
      rec.stage_times.push_back({"capture", vision::seconds_since(capture_start)});
      const std::string unverified = unverified_reason(status.position);
      if (unverified.empty()) return frames;
      if (attempt >= config_.capture.retries) throw PositionFailure{"settle", unverified};
      log_.event("settle", unverified + "; frames taken again", index);
      rec.stage_times.clear();
    }
  }

  // The position's frames (capture). A camera that fails is reopened
  // (reopen_camera) and the frames are taken again, once; a camera that does
  // not come back, or fails again, fails the position.
  std::vector<CapturedFrame> capture_reopening(std::int64_t index,
                                               std::chrono::system_clock::time_point settled_at) {
    try {
      return capture(settled_at);
    } catch (const vision::CaptureError& e) {
      if (const auto not_back = reopen_camera(index, e))
        throw PositionFailure{"camera", std::string(e.what()) + *not_back};
    }
    // The bench has not been told to move since: the read-back check after
    // these frames (unverified_reason) still vouches for them.
    try {
      return capture(settled_at);
    } catch (const vision::CaptureError& e) {
      throw PositionFailure{"camera", std::string(e.what()) + " (again, right after reopening)"};
    }
  }

  // The camera failed at position `index` with `lost`: it is closed and
  // opened again (the first attempt at once, then one every
  // faults.camera_reopen_interval) until it opens and delivers a frame of the
  // calibration's size (check_camera_frame), or faults.camera_reopen_timeout
  // has passed since the loss (an attempt under way then is finished). Returns
  // nothing when it is back, else why not ("" when reopening is off), to
  // follow the loss in the position's failure reason. A camera that comes back at another image
  // size ends the run (RunEnd): every frame would be measured with the wrong calibration.
  std::optional<std::string> reopen_camera(std::int64_t index, const vision::CaptureError& lost) {
    const auto timeout = config_.faults.camera_reopen_timeout;
    if (timeout.count() == 0) return std::string();
    log_.fault("camera", lost.what(), "reopen", index);
    const auto since = Clock::now();
    std::string last = lost.what();
    int attempt = 1;
    for (;; ++attempt) {
      camera_.close();
      try {
        camera_.open();
        check_camera_frame(camera_, config_);
        log_.event("camera",
                   "reopened at attempt " + std::to_string(attempt) + ", " +
                       std::to_string(vision::seconds_since(since)) + " s after the loss",
                   index);
        return std::nullopt;
      } catch (const vision::CaptureError& e) {
        last = e.what();
      } catch (const SweepConfigError& e) {
        throw RunEnd{db::store::RunStatus::kFailed, e.what()};
      }
      if (Clock::now() - since >= timeout) break;
      std::this_thread::sleep_for(config_.faults.camera_reopen_interval);
    }
    camera_.close();  // the next position tries again from a closed camera
    return "; not reopened within faults.camera_reopen_timeout_ms = " +
           std::to_string(timeout.count()) + " (" + std::to_string(attempt) +
           " attempts; last: " + last + ")";
  }

  // Triggers and grabs the position's frames after settled_at, handing each
  // to the FramePool as it arrives.
  std::vector<CapturedFrame> capture(std::chrono::system_clock::time_point settled_at) {
    std::vector<CapturedFrame> frames;
    for (int k = 0; k < config_.frames_per_position; ++k) {
      for (int discarded = 0;; ++discarded) {
        camera_.trigger();
        vision::Frame frame = camera_.grab(config_.grab_timeout);
        if (frame.host_time >= settled_at) {
          FramePool::Ticket measurement = pool_.submit(frame.image);
          frames.push_back({std::move(frame), std::move(measurement)});
          break;
        }
        if (discarded >= config_.capture.retries)
          throw PositionFailure{"camera", "only frames exposed before the bench settled arrived"};
      }
    }
    return frames;
  }

  // The read-back again: the frames count only if the bench stayed put. A
  // bench that cannot be read now cannot vouch for them either. Returns why
  // not, or "" when it stayed within the profile's position tolerance.
  std::string unverified_reason(const motion::XY& settled) {
    const double tolerance = config_.bench_profile.position_tolerance_mm;
    try {
      const motion::XY after = bench_.position();
      const double moved =
          std::max(std::abs(after.x_mm - settled.x_mm), std::abs(after.y_mm - settled.y_mm));
      if (moved <= tolerance) return "";
      return "the bench moved " + std::to_string(moved) + " mm during the exposures (tolerance " +
             std::to_string(tolerance) + " mm)";
    } catch (const motion::BenchError& e) {
      return std::string("the read-back after the exposures failed: ") + e.what();
    }
  }

  // The truth at the read-back (docs/target-and-geometry.md).
  // Returns the true T_cam_target.
  vision::Pose add_truth(db::store::PositionRecord& rec) const {
    const GroundTruth truth = ground_truth_at(config_.geometry, config_.camera, config_.target,
                                              *rec.measured_x_mm, *rec.measured_y_mm);
    rec.true_distance_m = truth.distance_m;
    rec.true_viewing_angle_deg = truth.viewing_angle_deg;
    rec.visible_markers = truth.visible_markers;
    rec.distance_bounds = truth.distance_bounds;
    rec.true_pose = stored_true_pose(truth.T_cam_target);
    return truth.T_cam_target;
  }

  // Every detector and every solver on each detector's corners for each
  // frame (measured by the FramePool, taken here in frame order), then, in
  // frame order on this thread, what must stay ordered: the log, the records
  // and every external estimator (on the primary detector's corners); with
  // the stage times: "detect" and "solve:SOLVER" of the primary detector,
  // "detect:DETECTOR" of each detector.
  void measure_frames(std::int64_t index, std::vector<CapturedFrame>& captured,
                      const vision::Pose& truth, db::store::PositionRecord& rec) {
    std::map<std::string, double> detect_s;
    std::map<std::string, double> solve_s;
    for (std::size_t k = 0; k < captured.size(); ++k) {
      const vision::FrameMeasurement m = pool_.take(captured[k].measurement);
      const vision::Frame& frame = captured[k].frame;
      // Detected corners no solver can take (e.g. outside the lens model's
      // invertible region): the scope has no estimates; say why.
      for (const vision::DetectorMeasurement& dm : m.detectors) {
        for (const auto& error : dm.scope_errors)
          log_.event("detect",
                     "frame " + std::to_string(k) + ", detector " + dm.detector + ", scope " +
                         error.scope + ": no estimates: " + error.message,
                     index);
        detect_s[dm.detector] += dm.detect_s;
      }
      for (const auto& [name, s] : m.primary().solve_s)
        solve_s[name] += s;
      rec.frames.push_back(frame_record(index, static_cast<int>(k), frame, m, truth));
      try {
        externals_.measure(index, frame.image, rec.frames.back().image_path, m, rec.frames.back(),
                           solve_s, log_);
      } catch (const std::runtime_error& e) {
        throw RunEnd{db::store::RunStatus::kFailed, e.what()};
      }
    }
    rec.stage_times.push_back({"detect", detect_s[measurer_.detector_names().front()]});
    for (const std::string& name : measurer_.detector_names())
      rec.stage_times.push_back({"detect:" + name, detect_s[name]});
    for (const auto& name : solver_names())
      rec.stage_times.push_back({"solve:" + name, solve_s[name]});
  }

  // What the run stores of frame k: the measurement, the frame's times and
  // source, and the saved PNG when frames are saved.
  db::store::FrameRecord frame_record(std::int64_t index, int k, const vision::Frame& frame,
                                      const vision::FrameMeasurement& m,
                                      const vision::Pose& truth) {
    db::store::FrameRecord f =
        to_frame_record(m, k, TrueCorners{config_.camera, config_.target, truth});
    if (frame.camera_timestamp_ns != 0)
      f.camera_timestamp_ns = static_cast<std::int64_t>(frame.camera_timestamp_ns);
    f.host_timestamp_ns = ns_since_epoch(frame.host_time);
    f.source = frame.origin.empty() ? camera_.name() : frame.origin;
    if (config_.frames_dir) {
      std::string sha;
      f.image_path = save_frame(index, k, frame.image, sha);
      f.image_sha256 = sha;
    }
    return f;
  }

  std::string save_frame(std::int64_t index, int k, const cv::Mat& image, std::string& sha) {
    const std::filesystem::path file =
        *frames_folder_ / ("p" + std::to_string(index) + "_f" + std::to_string(k) + ".png");
    std::vector<unsigned char> png;
    if (!vision::imencode(".png", image, png))
      throw RunEnd{db::store::RunStatus::kFailed,
                   "cannot encode frame as PNG for " + file.string()};
    const std::string_view bytes(reinterpret_cast<const char*>(png.data()), png.size());
    try {
      // The folder is this run's alone: a file at the path can only be left
      // by this run's interrupted position, and is replaced.
      write_new_file(file, bytes, /*replace_leftover=*/true);
    } catch (const std::runtime_error& e) {
      throw RunEnd{db::store::RunStatus::kFailed,
                   std::string(e.what()) + " (capture.save_frames " + *config_.frames_dir + ")"};
    }
    sha = db::store::sha256_hex(bytes);
    return file.string();
  }

  const SweepConfig& config_;
  const SweepPlan& plan_;
  motion::Bench& bench_;
  vision::FrameSource& camera_;
  RunLog& log_;
  FaultHandler& faults_;
  const vision::FrameMeasurer measurer_;
  FramePool pool_;               // measures with measurer_: declared after it, destroyed before it
  ExternalEstimates externals_;  // the sweep file's [[estimator]]s
  const std::optional<std::filesystem::path> frames_folder_;  // set when frames are saved
};

}  // namespace

// The run: every position it does not have, in plan order, each stored as
// it is measured; then how it ended.
struct Controller::Impl {
  const SweepConfig& config;
  const SweepPlan& plan;
  db::store::Store& store;
  const std::int64_t run_id;
  telemetry::ControlState& control;
  RunLog log;
  FaultHandler faults;
  PositionMeasurer positions;
  const Clock::time_point started = Clock::now();
  // Controller::retake_failed_positions: positions stored as failed are
  // measured again; `retakes` holds those still to measure, with the reason
  // each failed.
  bool retake_failed = false;
  std::map<std::int64_t, std::string> retakes;

  Impl(const SweepConfig& c, const SweepPlan& p, motion::Bench& b, vision::FrameSource& cam,
       db::store::Store& s, std::int64_t run, telemetry::ControlState& ctl,
       telemetry::TelemetryPublisher* t)
      : config(c),
        plan(p),
        store(s),
        run_id(run),
        control(ctl),
        log(s, run, static_cast<std::int64_t>(p.size()), t),
        faults(c.faults, b, ctl, log),
        positions(c, p, b, cam, log, faults,
                  c.frames_dir ? std::optional(run_frames_folder(*c.frames_dir, s.path(), run))
                               : std::nullopt) {}

  RunOutcome run() {
    RunOutcome outcome;
    const std::vector<bool> stored_already = start();
    int consecutive_failed = 0;
    std::optional<RunEnd> end;
    try {
      positions.prepare();
    } catch (const RunEnd& e) {
      end = e;
    }
    try {
      // Retakes replace stored records and record an event first: one at a time.
      const bool ahead = config.acquire_ahead && !retake_failed;
      if (!end && ahead) end = measure_ahead(stored_already, outcome, consecutive_failed);
      for (std::size_t i = 0; i < plan.size() && !end && !ahead; ++i) {
        if (stored_already[i]) continue;
        end = measure_and_store(static_cast<std::int64_t>(i), outcome, consecutive_failed);
      }
    } catch (const std::exception& e) {
      // The database or something unforeseen: leave the run resumable.
      finish(RunEnd{db::store::RunStatus::kFailed, e.what()}, outcome);
      throw;
    }
    finish(end ? *end : RunEnd{db::store::RunStatus::kCompleted, ""}, outcome);
    return outcome;
  }

  // Which positions the run has already, by plan index; publishes run_start.
  std::vector<bool> start() {
    const std::vector<std::int64_t> have = store.completed_position_indices(run_id);
    std::vector<bool> stored_already(plan.size(), false);
    for (std::int64_t i : have)
      stored_already[static_cast<std::size_t>(i)] = true;
    if (retake_failed)
      for (const db::store::PositionRecord& p : store.positions(run_id))
        if (p.status == db::store::PositionStatus::kFailed) {
          stored_already[static_cast<std::size_t>(p.plan_index)] = false;
          retakes[p.plan_index] = p.failure_reason;
        }
    log.set_stored(static_cast<std::int64_t>(have.size() - retakes.size()));
    std::int64_t first_index =
        store.first_incomplete_position(run_id).value_or(static_cast<std::int64_t>(plan.size()));
    if (!retakes.empty()) first_index = std::min(first_index, retakes.begin()->first);
    log.publish({{"type", "run_start"},
                 {"run_id", run_id},
                 {"database", store.path()},
                 {"plan_size", plan.size()},
                 {"first_index", first_index},
                 {"resumed", !have.empty()},
                 {"solvers", positions.solver_names()},
                 {"frames_per_position", config.frames_per_position},
                 {"sweep_file", config.sweep_file},
                 {"plan", plan.description()}});
    return stored_already;
  }

  // Position `index` after honouring a pause: measured, stored, published,
  // counted. Returns how the run ends when it ends here: aborted (before or
  // after the position, or after max_consecutive_failed failed positions in
  // a row) or as the position's RunEnd says.
  std::optional<RunEnd> measure_and_store(std::int64_t index, RunOutcome& outcome,
                                          int& consecutive_failed) {
    if (!faults.honour_pause(index))
      return RunEnd{db::store::RunStatus::kAborted,
                    faults.abort_reason("before position " + std::to_string(index))};
    log.set_current(index);
    const auto retake = retakes.find(index);
    if (retake != retakes.end())
      log.event("retake", "measuring again a position stored as failed: " + retake->second, index);
    db::store::PositionRecord rec;
    try {
      rec = positions.measure(index);
    } catch (const RunEnd& e) {
      return e;
    }
    return store_position(std::move(rec), outcome, consecutive_failed);
  }

  // SweepConfig::acquire_ahead: every position the run does not have, in
  // plan order, each acquired (moved to, settled, its frames taken and handed
  // to the FramePool) before the one before it is finished and stored, so
  // that its frames are measured meanwhile. What is recorded, and in which
  // order, is what measure_and_store records: acquiring records nothing
  // there (a replay's bench and frames), a position's failure is recorded
  // when it is finished, and a pause or an abort finishes the position
  // acquired first. Returns how the run ends when it ends early.
  std::optional<RunEnd> measure_ahead(const std::vector<bool>& stored_already, RunOutcome& outcome,
                                      int& consecutive_failed) {
    std::optional<PositionMeasurer::Acquired> pending;
    const auto complete = [&]() -> std::optional<RunEnd> {
      PositionMeasurer::Acquired a = std::move(*pending);
      pending.reset();
      log.set_current(a.rec.plan_index);
      db::store::PositionRecord rec;
      try {
        rec = positions.finish(std::move(a));
      } catch (const RunEnd& e) {
        return e;
      }
      return store_position(std::move(rec), outcome, consecutive_failed);
    };
    for (std::size_t i = 0; i < plan.size(); ++i) {
      if (stored_already[i]) continue;
      const auto index = static_cast<std::int64_t>(i);
      if (pending && (control.pause_requested() || control.abort_requested()))
        if (auto end = complete()) return end;
      if (!faults.honour_pause(index))
        return RunEnd{db::store::RunStatus::kAborted,
                      faults.abort_reason("before position " + std::to_string(index))};
      std::optional<PositionMeasurer::Acquired> next;
      try {
        next = positions.acquire(index);
      } catch (const RunEnd& e) {
        if (pending)
          if (auto end = complete()) return end;
        return e;
      }
      if (pending)
        if (auto end = complete()) return end;
      pending = std::move(next);
    }
    if (pending) return complete();
    return std::nullopt;
  }

  // A measured position stored (replacing its failed record when it is a
  // retake), published and counted. Returns how the run ends when it ends
  // here: after max_consecutive_failed failed positions in a row, or aborted.
  std::optional<RunEnd> store_position(db::store::PositionRecord rec, RunOutcome& outcome,
                                       int& consecutive_failed) {
    const auto retake = retakes.find(rec.plan_index);
    // The store times itself into the record (StoreOptions::record_store_time);
    // the whole append, commit included, goes to telemetry.
    const auto store_start = Clock::now();
    if (retake != retakes.end()) {
      store.retake_failed_position(run_id, rec);
      retakes.erase(retake);
    } else {
      store.append_position(run_id, rec);
    }
    rec.stage_times.push_back({"store_commit", vision::seconds_since(store_start)});
    log.count_stored(vision::seconds_since(started));
    nlohmann::json message = log.position_message(rec);
    message["database"] = store.path();  // a monitor that joins late still names it
    log.publish(message);
    if (rec.status == db::store::PositionStatus::kOk) {
      ++outcome.positions_ok;
      consecutive_failed = 0;
    } else {
      ++outcome.positions_failed;
      if (++consecutive_failed >= config.faults.max_consecutive_failed_positions)
        return RunEnd{db::store::RunStatus::kAborted,
                      std::to_string(consecutive_failed) +
                          " positions in a row failed (faults.max_consecutive_failed); last: " +
                          rec.failure_reason};
    }
    if (control.abort_requested())
      return RunEnd{db::store::RunStatus::kAborted,
                    faults.abort_reason("after position " + std::to_string(rec.plan_index))};
    return std::nullopt;
  }

  // Finishes the run in the store as `end` says (failed when it completed
  // with positions missing) and publishes run_stop.
  void finish(const RunEnd& end, RunOutcome& outcome) {
    outcome.status = end.status;
    outcome.reason = end.reason;
    outcome.stored_total = log.stored();
    if (end.status == db::store::RunStatus::kCompleted &&
        outcome.stored_total < static_cast<std::int64_t>(plan.size())) {
      outcome.status = db::store::RunStatus::kFailed;
      outcome.reason = "the plan ended with positions missing";
    }
    try {
      store.finish_run(run_id, outcome.status, outcome.reason);
    } catch (const db::store::StoreError&) {
      // Already failing on the database: the run stays "running" in the file,
      // which --resume accepts.
    }
    log.set_state("stopping");
    log.publish({{"type", "run_stop"},
                 {"run_id", run_id},
                 {"status", db::store::to_string(outcome.status)},
                 {"reason", outcome.reason},
                 {"positions_ok", outcome.positions_ok},
                 {"positions_failed", outcome.positions_failed},
                 {"stored", outcome.stored_total},
                 {"plan_size", plan.size()},
                 {"elapsed_s", vision::seconds_since(started)}});
  }
};

Controller::Controller(const SweepConfig& config, const SweepPlan& plan, motion::Bench& bench,
                       vision::FrameSource& camera, db::store::Store& store, std::int64_t run_id,
                       telemetry::ControlState& control, telemetry::TelemetryPublisher* telemetry)
    : impl_(
          std::make_unique<Impl>(config, plan, bench, camera, store, run_id, control, telemetry)) {}

Controller::~Controller() = default;

void Controller::set_observer(std::function<void(const nlohmann::json&)> observer) {
  impl_->log.set_observer(std::move(observer));
}

void Controller::retake_failed_positions() {
  impl_->retake_failed = true;
}

RunOutcome Controller::run() {
  return impl_->run();
}

nlohmann::json Controller::status() const {
  return impl_->log.status(impl_->control.paused());
}

}  // namespace rig::sweep
