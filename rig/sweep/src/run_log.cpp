#include "run_log.hpp"

#include <algorithm>
#include <utility>

#include "telemetry_messages.hpp"

namespace rig::sweep {

RunLog::RunLog(db::store::Store& store, std::int64_t run_id, std::int64_t plan_size,
               telemetry::TelemetryPublisher* telemetry)
    : store_(store),
      run_id_(run_id),
      plan_size_(plan_size),
      primary_detector_(store.run(run_id).description.primary_detector),
      telemetry_(telemetry) {}

void RunLog::set_observer(std::function<void(const nlohmann::json&)> observer) {
  observer_ = std::move(observer);
}

void RunLog::publish(const nlohmann::json& message) {
  if (telemetry_ && !telemetry_failed_) {
    try {
      telemetry_->publish(message);
    } catch (const telemetry::TelemetryError& e) {
      telemetry_failed_ = true;
      store_.record_event(run_id_, "telemetry",
                          std::string(e.what()) + "; telemetry off for the rest of the run");
    }
  }
  if (observer_) observer_(message);
}

void RunLog::event(const std::string& kind, const std::string& message,
                   std::optional<std::int64_t> plan_index) {
  store_.record_event(run_id_, kind, message, plan_index);
}

void RunLog::fault(const std::string& kind, const std::string& message, const std::string& action,
                   std::optional<std::int64_t> plan_index) {
  store_.record_event(run_id_, kind, message + " (" + action + ")", plan_index);
  publish({{"type", "fault"},
           {"run_id", run_id_},
           {"plan_index", plan_index ? nlohmann::json(*plan_index) : nlohmann::json(nullptr)},
           {"kind", kind},
           {"message", message},
           {"action", action}});
}

void RunLog::set_state(const std::string& state) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (state_ == state) return;
    state_ = state;
  }
  publish({{"type", "state"}, {"run_id", run_id_}, {"state", state}});
}

void RunLog::set_stored(std::int64_t stored) {
  std::lock_guard<std::mutex> lock(mutex_);
  stored_ = stored;
}

void RunLog::set_current(std::int64_t plan_index) {
  std::lock_guard<std::mutex> lock(mutex_);
  current_index_ = plan_index;
}

void RunLog::count_stored(double elapsed_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++stored_;
  ++done_this_session_;
  elapsed_s_ = elapsed_s;
}

void RunLog::add_paused(double seconds) {
  std::lock_guard<std::mutex> lock(mutex_);
  paused_s_ += seconds;
}

std::int64_t RunLog::stored() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stored_;
}

nlohmann::json RunLog::position_message(const db::store::PositionRecord& position) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return rig::sweep::position_message(position, primary_detector_, run_id_, stored_, plan_size_,
                                      elapsed_s_);
}

double RunLog::eta_s() const {
  if (done_this_session_ == 0) return -1;
  const double per_position =
      std::max(0.0, elapsed_s_ - paused_s_) / static_cast<double>(done_this_session_);
  return per_position * static_cast<double>(plan_size_ - stored_);
}

nlohmann::json RunLog::status(bool holding) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const double eta = eta_s();
  return {{"state", holding && state_ == "running" ? "paused" : state_},
          {"run_id", run_id_},
          {"completed", stored_},
          {"plan_size", plan_size_},
          {"current_index", current_index_},
          {"eta_s", eta < 0 ? nlohmann::json(nullptr) : nlohmann::json(eta)}};
}

}  // namespace rig::sweep
