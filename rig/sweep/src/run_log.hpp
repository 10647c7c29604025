// The bookkeeping of one run while the Controller measures it: the run's
// events and faults in the store, its telemetry (to subscribers and to the
// observer) and the progress the control socket's `status` reports
// (docs/telemetry.md).
#pragma once

#include <cstdint>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "db/store/store.hpp"
#include "rig/telemetry/telemetry.hpp"

namespace rig::sweep {

class RunLog {
 public:
  // `telemetry` may be null. store and telemetry must outlive the RunLog.
  RunLog(db::store::Store& store, std::int64_t run_id, std::int64_t plan_size,
         telemetry::TelemetryPublisher* telemetry);

  std::int64_t run_id() const { return run_id_; }

  // Also hands every message to `observer` (on the publishing thread).
  void set_observer(std::function<void(const nlohmann::json&)> observer);

  // Publishes one telemetry message. Telemetry never ends a sweep: the first
  // socket error is recorded as a "telemetry" event and the run goes on
  // without telemetry; the observer still sees every message.
  void publish(const nlohmann::json& message);
  // Records an event of the run (db::store::Store::record_event).
  void event(const std::string& kind, const std::string& message,
             std::optional<std::int64_t> plan_index = std::nullopt);
  // A fault and what the controller does about it ("retry", "pause",
  // "abort", "position_failed"): recorded as the event "MESSAGE (ACTION)" and
  // published as a "fault" message.
  void fault(const std::string& kind, const std::string& message, const std::string& action,
             std::optional<std::int64_t> plan_index);
  // "running", "paused" or "stopping"; publishes a "state" message when it changes.
  void set_state(const std::string& state);

  // Progress. The run has `stored` positions when the session starts.
  void set_stored(std::int64_t stored);
  // The position being measured.
  void set_current(std::int64_t plan_index);
  // One more position stored in this session, `elapsed_s` seconds after it started.
  void count_stored(double elapsed_s);
  // Seconds spent paused in this session, not counted in the ETA.
  void add_paused(double seconds);
  // Positions the run has (all sessions).
  std::int64_t stored() const;

  // The "position" message of a stored position (telemetry_messages.hpp).
  nlohmann::json position_message(const db::store::PositionRecord& position) const;
  // {"state", "run_id", "completed", "plan_size", "current_index", "eta_s"}:
  // "paused" while `holding` (ControlState::paused) and running; eta_s null
  // before the session stored a position. Thread-safe.
  nlohmann::json status(bool holding) const;

 private:
  double eta_s() const;  // under mutex_; -1 before the first position of the session

  db::store::Store& store_;
  const std::int64_t run_id_;
  const std::int64_t plan_size_;
  const std::string primary_detector_;  // the run's, whose estimates telemetry shows
  telemetry::TelemetryPublisher* telemetry_;
  bool telemetry_failed_ = false;
  std::function<void(const nlohmann::json&)> observer_;

  mutable std::mutex mutex_;  // guards the progress below, read by status()
  std::string state_ = "running";
  std::int64_t stored_ = 0;
  std::int64_t current_index_ = -1;
  std::int64_t done_this_session_ = 0;
  double elapsed_s_ = 0;
  double paused_s_ = 0;
};

}  // namespace rig::sweep
