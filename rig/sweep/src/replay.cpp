#include "rig/sweep/replay.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <utility>

#include "config/json.hpp"
#include "db/store/saved_frame.hpp"
#include "motion/errors.hpp"
#include "rig/sweep/run_record.hpp"
#include "vision/detector_image.hpp"

namespace rig::sweep {
namespace {

// The shortest text that reads back as the same double: an XY that misses a
// plan position by 1e-9 mm must not print as that position.
std::string exact(double v) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  return ec == std::errc() ? std::string(buffer, end) : std::to_string(v);
}

std::string xy_text(double x_mm, double y_mm) {
  return "(" + exact(x_mm) + ", " + exact(y_mm) + ") mm";
}

// Reads a saved frame: the file's bytes, their SHA-256 checked against the
// stored one, then decoded unchanged. Returns an empty image and sets `error`
// (naming the file and what is wrong) when any step fails.
cv::Mat read_recorded_frame(const RecordedFrame& f, std::string& error) {
  try {
    const std::string bytes = db::store::read_saved_frame(f.image_path, f.image_sha256);
    return vision::decode_image(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(),
                                cv::IMREAD_UNCHANGED, "recorded frame " + f.image_path);
  } catch (const db::store::SavedFrameError& e) {
    error = e.what();
  } catch (const vision::ImageError& e) {
    error = e.what();
  }
  return {};
}

}  // namespace

RecordedRun RecordedRun::load(const db::store::Store& store, std::int64_t run_id) {
  RecordedRun r;
  r.database_ = store.path();
  r.run_ = store.run(run_id);
  const nlohmann::json plan = parse_stored_json(r.run_.description.plan_json);
  if (plan.is_discarded())
    throw PlanError("run " + std::to_string(run_id) +
                    ": its stored plan is not valid JSON; the database is damaged");
  r.plan_ = SweepPlan::from_json(plan);
  r.positions_.resize(r.plan_.size());
  for (std::size_t i = 0; i < r.plan_.size(); ++i) {
    RecordedPosition& p = r.positions_[i];
    p.plan_index = static_cast<std::int64_t>(i);
    p.commanded_x_mm = r.plan_.positions()[i].x_mm;
    p.commanded_y_mm = r.plan_.positions()[i].y_mm;
  }
  for (const std::int64_t index : store.completed_position_indices(run_id)) {
    if (index < 0 || index >= static_cast<std::int64_t>(r.positions_.size())) continue;
    const db::store::PositionRecord stored = store.position(run_id, index);
    RecordedPosition& p = r.positions_[static_cast<std::size_t>(index)];
    p.stored = true;
    p.measured_x_mm = stored.measured_x_mm;
    p.measured_y_mm = stored.measured_y_mm;
    p.status = stored.status;
    p.failure_reason = stored.failure_reason;
    for (const db::store::FrameRecord& f : stored.frames) {
      if (!f.image_path || !f.image_sha256) continue;
      p.frames.push_back({f.index, *f.image_path, *f.image_sha256});
    }
    std::sort(p.frames.begin(), p.frames.end(),
              [](const RecordedFrame& a, const RecordedFrame& b) { return a.index < b.index; });
  }
  return r;
}

int RecordedRun::saved_frames_per_position() const {
  int fewest = 0;
  for (const RecordedPosition& p : positions_) {
    if (p.status != db::store::PositionStatus::kOk || p.frames.empty()) continue;
    const int n = static_cast<int>(p.frames.size());
    fewest = fewest == 0 ? n : std::min(fewest, n);
  }
  return fewest;
}

nlohmann::json RecordedRun::replay_of() const {
  const nlohmann::json config = parse_stored_json(run_.description.config_json);
  if (config.is_object() && config.contains("replay_of")) return config["replay_of"];
  return nullptr;
}

std::string RecordedRun::describe() const {
  return "run " + std::to_string(run_.id) + " of " + database_;
}

std::string RecordedRun::why_missing(std::int64_t plan_index) const {
  const RecordedPosition& p = positions_.at(static_cast<std::size_t>(plan_index));
  if (p.stored && p.status == db::store::PositionStatus::kFailed)
    return "it failed: " + p.failure_reason;
  if (p.stored) return "the run saved no frames for it";
  if (run_.status == db::store::RunStatus::kRunning)
    return "it was never measured (run " + std::to_string(run_.id) + " is still running)";
  return "it was never measured (run " + std::to_string(run_.id) + " ended " +
         db::store::to_string(run_.status) +
         (run_.status_reason.empty() ? "" : ": " + run_.status_reason) + ")";
}

ReplayCursor::ReplayCursor(std::shared_ptr<const RecordedRun> run)
    : run_(std::move(run)), settled_(run_->positions().size(), false) {}

void ReplayCursor::select(double x_mm, double y_mm) {
  if (!std::isfinite(x_mm) || !std::isfinite(y_mm))
    throw motion::SoftLimitError("replay: move to " + xy_text(x_mm, y_mm) +
                                 ": expected finite coordinates");
  const auto& positions = run_->positions();
  std::optional<std::size_t> first, first_unsettled;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const RecordedPosition& p = positions[i];
    if (std::abs(p.commanded_x_mm - x_mm) > kXyMatchMm ||
        std::abs(p.commanded_y_mm - y_mm) > kXyMatchMm)
      continue;
    if (!first) first = i;
    if (!settled_[i]) {
      first_unsettled = i;
      break;
    }
  }
  if (!first)
    throw motion::SoftLimitError("replay: move to " + xy_text(x_mm, y_mm) + ": the plan of " +
                                 run_->describe() + " has no position commanded there (within " +
                                 std::to_string(kXyMatchMm) + " mm); expected one of its " +
                                 std::to_string(positions.size()) + " plan positions");
  selected_ = first_unsettled ? first_unsettled : first;
  next_frame_ = 0;
}

const RecordedPosition* ReplayCursor::selected() const {
  return selected_ ? &run_->positions()[*selected_] : nullptr;
}

void ReplayCursor::mark_settled() {
  if (selected_) settled_[*selected_] = true;
}

ReplayBench::ReplayBench(std::shared_ptr<ReplayCursor> cursor) : cursor_(std::move(cursor)) {}

void ReplayBench::move_to(double x_mm, double y_mm) {
  cursor_->select(x_mm, y_mm);
}

motion::BenchStatus ReplayBench::wait_settled(std::chrono::milliseconds /*timeout*/) {
  const RecordedPosition* p = cursor_->selected();
  if (p) {
    cursor_->mark_settled();
    if (!p->measured_x_mm || !p->measured_y_mm)
      throw motion::BenchTimeout("position " + std::to_string(p->plan_index) + " of " +
                                 cursor_->run().describe() + " has no recorded read-back (" +
                                 cursor_->run().why_missing(p->plan_index) + ")");
    position_ = {*p->measured_x_mm, *p->measured_y_mm};
  }
  return status();
}

motion::XY ReplayBench::position() {
  return position_;
}

motion::BenchStatus ReplayBench::status() {
  motion::BenchStatus s;
  s.position = position_;
  s.homed = true;
  s.in_position = true;
  return s;
}

ReplayFrames::ReplayFrames(std::shared_ptr<ReplayCursor> cursor) : cursor_(std::move(cursor)) {}

std::string ReplayFrames::name() const {
  return "replay of " + cursor_->run().describe();
}

vision::Frame ReplayFrames::grab(std::chrono::milliseconds /*timeout*/) {
  if (!open_) throw vision::CaptureError(name(), "grab before open()");
  const RecordedPosition* p = cursor_->selected();
  if (!p) throw vision::CaptureError(name(), "grab before the bench was moved to a position");
  // name() says which run; the message says where in it.
  const std::string where = "position " + std::to_string(p->plan_index);
  if (p->frames.empty())
    throw vision::CaptureError(name(), where + " has no recorded frames (" +
                                           cursor_->run().why_missing(p->plan_index) + ")");
  const int k = cursor_->next_frame();
  if (k >= static_cast<int>(p->frames.size()))
    throw vision::EndOfFrames(name(), where + " has only " + std::to_string(p->frames.size()) +
                                          " recorded frames; frame " + std::to_string(k) +
                                          " was asked for");
  cursor_->advance_frame();
  const RecordedFrame& f = p->frames[static_cast<std::size_t>(k)];
  vision::Frame frame;
  std::string error;
  frame.image = read_recorded_frame(f, error);
  if (frame.image.empty()) {
    ++counters_.incomplete;
    throw vision::CaptureError(name(), where + ", frame " + std::to_string(f.index) + ": " + error);
  }
  frame.frame_id = static_cast<std::uint64_t>(f.index);
  frame.host_time = std::chrono::system_clock::now();
  frame.origin = f.image_path;
  ++counters_.delivered;
  return frame;
}

SweepConfig replay_config(const SweepConfig& config, const RecordedRun& recorded) {
  const int saved = recorded.saved_frames_per_position();
  if (saved == 0) {
    const nlohmann::json original = recorded.replay_of();
    if (!original.is_null())
      throw RunMismatch(recorded.describe() + " saved no frames: it is a replay of run " +
                        config::excerpt_json(original.value("run", nlohmann::json())) + " of " +
                        original.value("database", std::string("?")) +
                        " (a replay names the original PNGs as frame sources); replay that run");
    throw RunMismatch(recorded.describe() +
                      " saved no frames (set [capture] save_frames in the sweep file)");
  }
  if (config.frames_per_position > saved)
    throw RunMismatch(
        config.sweep_file +
        ": capture.frames_per_position = " + std::to_string(config.frames_per_position) + " but " +
        recorded.describe() + " saved " + std::to_string(saved) +
        " frames per position; expected at most " + std::to_string(saved) + " for a replay of it");

  // The first frame that reads and verifies gives the recorded image size;
  // frames that do not are the replay's failed positions, not a reason to refuse.
  std::string first_error;
  for (const RecordedPosition& p : recorded.positions()) {
    for (const RecordedFrame& f : p.frames) {
      std::string error;
      const cv::Mat image = read_recorded_frame(f, error);
      if (image.empty()) {
        if (first_error.empty()) first_error = error;
        continue;
      }
      if (const auto mismatch = config.camera.image_size_mismatch(
              image.size(), "frame " + f.image_path + " of " + recorded.describe(),
              config.calibration_description()))
        throw RunMismatch(config.sweep_file + ": capture.calibration: " + *mismatch +
                          "; expected the calibration of the camera that recorded it");
      SweepConfig replay = config;
      replay.frames_dir.reset();
      // Saved frames are files: there is no camera to reopen.
      replay.faults.camera_reopen_timeout = std::chrono::milliseconds(0);
      // Its bench and frames record nothing while a position is acquired.
      replay.acquire_ahead = true;
      replay.faults.max_consecutive_failed_positions = static_cast<int>(
          std::min<std::size_t>(recorded.plan().size() + 1, std::numeric_limits<int>::max()));
      return replay;
    }
  }
  throw RunMismatch("none of the saved frames of " + recorded.describe() +
                    " reads and verifies; first: " + first_error);
}

}  // namespace rig::sweep
