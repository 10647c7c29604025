#include "rig/sweep/controller.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <sstream>
#include <thread>
#include <utility>
#include <vector>

#include "db/store/sha256.hpp"
#include "motion/errors.hpp"
#include "rig/sweep/ground_truth.hpp"
#include "telemetry_messages.hpp"
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

}  // namespace

struct Controller::Impl {
  const SweepConfig& config;
  const SweepPlan& plan;
  motion::Bench& bench;
  vision::FrameSource& camera;
  db::store::Store& store;
  std::int64_t run_id;
  telemetry::ControlState& control;
  telemetry::TelemetryPublisher* telemetry;
  vision::FrameMeasurer measurer;

  mutable std::mutex mutex;  // guards the status fields below
  std::string state = "running";
  std::int64_t stored = 0;  // positions the run has
  std::int64_t current_index = -1;
  std::int64_t done_this_session = 0;
  double elapsed_s = 0;
  Clock::time_point started = Clock::now();

  Impl(const SweepConfig& c, const SweepPlan& p, motion::Bench& b, vision::FrameSource& cam,
       db::store::Store& s, std::int64_t run, telemetry::ControlState& ctl,
       telemetry::TelemetryPublisher* t)
      : config(c),
        plan(p),
        bench(b),
        camera(cam),
        store(s),
        run_id(run),
        control(ctl),
        telemetry(t),
        measurer(c.camera, c.target) {}

  std::function<void(const nlohmann::json&)> observer;

  bool telemetry_failed = false;

  // Telemetry never ends a sweep: a socket error is recorded once and the
  // sweep goes on without it.
  void publish(const nlohmann::json& message) {
    if (telemetry && !telemetry_failed) {
      try {
        telemetry->publish(message);
      } catch (const telemetry::TelemetryError& e) {
        telemetry_failed = true;
        store.record_event(run_id, "telemetry",
                           std::string(e.what()) + "; telemetry off for the rest of the run");
      }
    }
    if (observer) observer(message);
  }

  void set_state(const std::string& s) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (state == s) return;
      state = s;
    }
    publish({{"type", "state"}, {"run_id", run_id}, {"state", s}});
  }

  void fault(const std::string& kind, const std::string& message, const std::string& action,
             std::optional<std::int64_t> index) {
    store.record_event(run_id, kind, message + " (" + action + ")", index);
    publish({{"type", "fault"},
             {"run_id", run_id},
             {"plan_index", index ? nlohmann::json(*index) : nlohmann::json(nullptr)},
             {"kind", kind},
             {"message", message},
             {"action", action}});
  }

  double paused_s = 0;  // time spent paused in this session (not measuring)

  double eta_s() const {  // under mutex
    if (done_this_session == 0) return -1;
    const double per_position =
        std::max(0.0, elapsed_s - paused_s) / static_cast<double>(done_this_session);
    return per_position * static_cast<double>(static_cast<std::int64_t>(plan.size()) - stored);
  }

  // Waits out a pause (requested, or after an alarm). Returns false when the
  // run is to be aborted.
  bool honour_pause(std::optional<std::int64_t> index) {
    if (control.abort_requested()) return false;
    if (!control.pause_requested()) return true;
    store.record_event(run_id, "pause",
                       control.paused_by_controller() ? "paused after a fault" : "pause requested",
                       index);
    set_state("paused");
    const auto pause_start = Clock::now();
    const bool go_on = control.wait_while_paused();
    {
      std::lock_guard<std::mutex> lock(mutex);
      paused_s += vision::seconds_since(pause_start);
    }
    if (!go_on) return false;
    store.record_event(run_id, "resume", "resumed", index);
    set_state("running");
    return true;
  }

  // Moves to the position and waits until settled; handles alarms and link
  // drops per policy. Returns the settled status and the settle time.
  std::pair<motion::BenchStatus, double> move_and_settle(std::int64_t index, const PlanPosition& p,
                                                         db::store::PositionRecord& rec) {
    int link_failures = 0;
    for (;;) {
      try {
        const auto move_start = Clock::now();
        bench.move_to(p.x_mm, p.y_mm);
        const double move_s = vision::seconds_since(move_start);
        const auto settle_start = Clock::now();
        const motion::BenchStatus status = bench.wait_settled(config.settle.timeout);
        const double settle_s = vision::seconds_since(settle_start);
        rec.stage_times.push_back({"move", move_s});
        rec.stage_times.push_back({"settle", settle_s});
        return {status, move_s + settle_s};
      } catch (const motion::BenchFault& e) {
        try {
          bench.stop();
        } catch (const motion::BenchError&) {
          // The alarm is what we report; a failing stop adds nothing.
        }
        if (config.faults.on_alarm == AlarmAction::kAbort) {
          fault("alarm", e.what(), "abort", index);
          throw RunEnd{db::store::RunStatus::kAborted, std::string("bench alarm: ") + e.what()};
        }
        fault("alarm", e.what(), "pause", index);
        control.set_paused_by_controller(true);
        if (!honour_pause(index))
          throw RunEnd{db::store::RunStatus::kAborted, abort_reason("after a bench alarm")};
        try {
          bench.reset_alarm();
        } catch (const motion::BenchFault& again) {
          fault("alarm", std::string("alarm persists after reset: ") + again.what(), "pause",
                index);
          control.set_paused_by_controller(true);
        } catch (const motion::BenchLinkError& e) {
          // The move is retried next; a link that stays down ends there.
          fault("link", std::string("resetting the alarm: ") + e.what(), "retry", index);
        }
      } catch (const motion::BenchLinkError& e) {
        ++link_failures;
        if (link_failures > config.faults.link_retries) {
          fault("link", e.what(), "abort", index);
          throw RunEnd{
              db::store::RunStatus::kFailed,
              "bench link lost after " + std::to_string(link_failures) + " attempts: " + e.what()};
        }
        fault("link", e.what(), "retry", index);
      } catch (const motion::BenchTimeout& e) {
        throw PositionFailure{"settle", e.what()};
      } catch (const motion::SoftLimitError& e) {
        // load_sweep_config checked every position against the same limits.
        throw RunEnd{db::store::RunStatus::kFailed, e.what()};
      }
    }
  }

  std::string abort_reason(const std::string& context) const {
    const std::string reason = control.abort_reason();
    return (reason.empty() ? std::string("aborted") : reason) + " (" + context + ")";
  }

  // Triggers and grabs the position's frames after settled_at.
  std::vector<vision::Frame> capture(std::chrono::system_clock::time_point settled_at) {
    std::vector<vision::Frame> frames;
    for (int k = 0; k < config.frames_per_position; ++k) {
      for (int discarded = 0;; ++discarded) {
        camera.trigger();
        vision::Frame frame = camera.grab(config.faults.grab_timeout);
        if (frame.host_time >= settled_at) {
          frames.push_back(std::move(frame));
          break;
        }
        if (discarded >= config.faults.capture_retries)
          throw PositionFailure{"camera", "only frames exposed before the bench settled arrived"};
      }
    }
    return frames;
  }

  std::string save_frame(std::int64_t index, int k, const cv::Mat& image, std::string& sha) {
    namespace fs = std::filesystem;
    const fs::path dir = fs::path(*config.frames_dir) / ("run" + std::to_string(run_id));
    fs::create_directories(dir);
    const fs::path file = dir / ("p" + std::to_string(index) + "_f" + std::to_string(k) + ".png");
    std::vector<unsigned char> png;
    if (!cv::imencode(".png", image, png))
      throw RunEnd{db::store::RunStatus::kFailed,
                   "cannot encode frame as PNG for " + file.string()};
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
    out.close();
    if (!out)
      throw RunEnd{db::store::RunStatus::kFailed, "cannot write frame " + file.string() +
                                                      " (frames_dir " + *config.frames_dir + ")"};
    sha = db::store::sha256_hex(
        std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
    return file.string();
  }

  db::store::PositionRecord measure_position(std::int64_t index) {
    const PlanPosition& p = plan.positions()[static_cast<std::size_t>(index)];
    db::store::PositionRecord rec;
    rec.plan_index = index;
    rec.commanded_x_mm = p.x_mm;
    rec.commanded_y_mm = p.y_mm;
    try {
      std::vector<vision::Frame> frames;
      motion::BenchStatus settled;
      const double tolerance = config.bench_profile.position_tolerance_mm;
      for (int attempt = 0;; ++attempt) {
        const auto [status, settle_s] = move_and_settle(index, p, rec);
        settled = status;
        rec.settle_time_s = settle_s;
        rec.measured_x_mm = status.position.x_mm;
        rec.measured_y_mm = status.position.y_mm;
        const auto settled_at = std::chrono::system_clock::now();
        if (config.settle.dwell.count() > 0) std::this_thread::sleep_for(config.settle.dwell);
        const auto capture_start = Clock::now();
        try {
          frames = capture(settled_at);
        } catch (const vision::CaptureError& e) {
          throw PositionFailure{"camera", e.what()};
        }
        rec.stage_times.push_back({"capture", vision::seconds_since(capture_start)});
        // The read-back again: the frames count only if the bench stayed put.
        // A bench that cannot be read now cannot vouch for them either.
        std::string unverified;
        try {
          const motion::XY after = bench.position();
          const double moved = std::max(std::abs(after.x_mm - status.position.x_mm),
                                        std::abs(after.y_mm - status.position.y_mm));
          if (moved <= tolerance) break;
          unverified = "the bench moved " + std::to_string(moved) +
                       " mm during the exposures (tolerance " + std::to_string(tolerance) + " mm)";
        } catch (const motion::BenchError& e) {
          unverified = std::string("the read-back after the exposures failed: ") + e.what();
        }
        if (attempt >= config.faults.capture_retries) throw PositionFailure{"settle", unverified};
        store.record_event(run_id, "settle", unverified + "; frames taken again", index);
        rec.stage_times.clear();
      }

      const GroundTruth truth = ground_truth_at(config.geometry, config.camera, config.target,
                                                *rec.measured_x_mm, *rec.measured_y_mm);
      rec.true_distance_m = truth.distance_m;
      rec.true_viewing_angle_deg = truth.viewing_angle_deg;
      rec.visible_markers = truth.visible_markers;
      rec.distance_bounds = truth.distance_bounds;

      double detect_s = 0;
      std::map<std::string, double> solve_s;
      for (std::size_t k = 0; k < frames.size(); ++k) {
        const vision::FrameMeasurement m = measurer.measure(frames[k].image);
        // Detected corners no solver can take (e.g. outside the lens model's
        // invertible region): the scope has no estimates; say why.
        for (const auto& error : m.scope_errors)
          store.record_event(run_id, "detect",
                             "frame " + std::to_string(k) + ", scope " + error.scope +
                                 ": no estimates: " + error.message,
                             index);
        detect_s += m.detect_s;
        for (const auto& [name, s] : m.solve_s)
          solve_s[name] += s;
        db::store::FrameRecord f = to_frame_record(m, static_cast<int>(k));
        if (frames[k].camera_timestamp_ns != 0)
          f.camera_timestamp_ns = static_cast<std::int64_t>(frames[k].camera_timestamp_ns);
        f.host_timestamp_ns = ns_since_epoch(frames[k].host_time);
        f.source = frames[k].origin.empty() ? camera.name() : frames[k].origin;
        if (config.frames_dir) {
          std::string sha;
          f.image_path = save_frame(index, static_cast<int>(k), frames[k].image, sha);
          f.image_sha256 = sha;
        }
        rec.frames.push_back(std::move(f));
      }
      rec.stage_times.push_back({"detect", detect_s});
      for (const auto& name : measurer.solver_names())
        rec.stage_times.push_back({"solve:" + name, solve_s[name]});
      rec.status = db::store::PositionStatus::kOk;
    } catch (const PositionFailure& f) {
      fault(f.kind, f.reason, "position_failed", index);
      rec.status = db::store::PositionStatus::kFailed;
      rec.failure_reason = f.kind + ": " + f.reason;
      rec.frames.clear();
    }
    return rec;
  }

  nlohmann::json position_message(const db::store::PositionRecord& rec) const {
    std::lock_guard<std::mutex> lock(mutex);
    return rig::sweep::position_message(rec, run_id, stored, static_cast<std::int64_t>(plan.size()),
                                        elapsed_s);
  }

  RunOutcome run() {
    RunOutcome outcome;
    const std::vector<std::int64_t> have = store.completed_position_indices(run_id);
    std::vector<bool> stored_already(plan.size(), false);
    for (std::int64_t i : have)
      stored_already[static_cast<std::size_t>(i)] = true;
    {
      std::lock_guard<std::mutex> lock(mutex);
      stored = static_cast<std::int64_t>(have.size());
    }
    const std::int64_t first_index =
        store.first_incomplete_position(run_id).value_or(static_cast<std::int64_t>(plan.size()));
    publish({{"type", "run_start"},
             {"run_id", run_id},
             {"database", store.path()},
             {"plan_size", plan.size()},
             {"first_index", first_index},
             {"resumed", !have.empty()},
             {"solvers", measurer.solver_names()},
             {"frames_per_position", config.frames_per_position},
             {"sweep_file", config.sweep_file},
             {"plan", plan.description()}});
    int consecutive_failed = 0;
    std::optional<RunEnd> end;
    try {
      for (std::size_t i = 0; i < plan.size() && !end; ++i) {
        if (stored_already[i]) continue;
        const auto index = static_cast<std::int64_t>(i);
        if (!honour_pause(index)) {
          end = RunEnd{db::store::RunStatus::kAborted,
                       abort_reason("before position " + std::to_string(index))};
          break;
        }
        {
          std::lock_guard<std::mutex> lock(mutex);
          current_index = index;
        }
        db::store::PositionRecord rec;
        try {
          rec = measure_position(index);
        } catch (const RunEnd& e) {
          end = e;
          break;
        }
        // The store times itself into the record (StoreOptions::record_store_time);
        // the whole append, commit included, goes to telemetry.
        const auto store_start = Clock::now();
        store.append_position(run_id, rec);
        rec.stage_times.push_back({"store_commit", vision::seconds_since(store_start)});
        {
          std::lock_guard<std::mutex> lock(mutex);
          ++stored;
          ++done_this_session;
          elapsed_s = vision::seconds_since(started);
        }
        publish(position_message(rec));
        if (rec.status == db::store::PositionStatus::kOk) {
          ++outcome.positions_ok;
          consecutive_failed = 0;
        } else {
          ++outcome.positions_failed;
          if (++consecutive_failed >= config.faults.max_consecutive_failed_positions)
            end = RunEnd{db::store::RunStatus::kAborted,
                         std::to_string(consecutive_failed) +
                             " positions in a row failed (faults.max_consecutive_failed); last: " +
                             rec.failure_reason};
        }
        if (!end && control.abort_requested())
          end = RunEnd{db::store::RunStatus::kAborted,
                       abort_reason("after position " + std::to_string(index))};
      }
    } catch (const std::exception& e) {
      // The database or something unforeseen: leave the run resumable.
      finish(RunEnd{db::store::RunStatus::kFailed, e.what()}, outcome);
      throw;
    }
    finish(end ? *end : RunEnd{db::store::RunStatus::kCompleted, ""}, outcome);
    return outcome;
  }

  void finish(const RunEnd& end, RunOutcome& outcome) {
    outcome.status = end.status;
    outcome.reason = end.reason;
    {
      std::lock_guard<std::mutex> lock(mutex);
      outcome.stored_total = stored;
    }
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
    set_state("stopping");
    publish({{"type", "run_stop"},
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
  impl_->observer = std::move(observer);
}

RunOutcome Controller::run() {
  return impl_->run();
}

nlohmann::json Controller::status() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  const double eta = impl_->eta_s();
  return {{"state", impl_->control.paused() && impl_->state == "running" ? "paused" : impl_->state},
          {"run_id", impl_->run_id},
          {"completed", impl_->stored},
          {"plan_size", impl_->plan.size()},
          {"current_index", impl_->current_index},
          {"eta_s", eta < 0 ? nlohmann::json(nullptr) : nlohmann::json(eta)}};
}

}  // namespace rig::sweep
