#include "rig/estimator/external_estimator.hpp"

#include <nlohmann/json.hpp>

#include "protocol.hpp"
#include "rig/estimator/child_process.hpp"
#include "vision/timing.hpp"

namespace rig::estimator {

using Clock = ChildProcess::Clock;

const char* to_string(FailureKind kind) {
  switch (kind) {
    case FailureKind::kStart:
      return "start";
    case FailureKind::kProtocol:
      return "protocol";
    case FailureKind::kCrash:
      return "crash";
    case FailureKind::kTimeout:
      return "timeout";
    case FailureKind::kMalformed:
      return "malformed";
    case FailureKind::kDeclined:
      return "declined";
    case FailureKind::kDisabled:
      return "disabled";
  }
  return "unknown";
}

std::string camera_json(const vision::Camera& camera) {
  const vision::Intrinsics& k = camera.intrinsics();
  // OpenCV's order, as cv::solvePnP takes it: 5 values, 12 with a thin prism.
  const cv::Mat d = camera.distortion_cv();
  return nlohmann::json{{"width_px", camera.width_px()},
                        {"height_px", camera.height_px()},
                        {"K", {{k.fx, 0.0, k.cx}, {0.0, k.fy, k.cy}, {0.0, 0.0, 1.0}}},
                        {"distortion", std::vector<double>(d.begin<double>(), d.end<double>())}}
      .dump();
}

std::string target_json(const vision::Target& target) {
  nlohmann::json markers = nlohmann::json::array();
  for (const vision::TargetMarker& m : target.markers) {
    nlohmann::json corners = nlohmann::json::array();
    for (const Eigen::Vector3d& c : target.corners_m(m))
      corners.push_back({c.x(), c.y(), c.z()});
    markers.push_back({{"id", m.id}, {"side_m", m.side_m}, {"corners_m", std::move(corners)}});
  }
  return nlohmann::json{
      {"name", target.name}, {"pose_marker", target.pose_marker_id}, {"markers", markers}}
      .dump();
}

struct ExternalEstimator::Process {
  Process(const std::vector<std::string>& argv, const std::string& dir) : child(argv, dir) {}
  ChildProcess child;
};

ExternalEstimator::ExternalEstimator(EstimatorSpec spec, const vision::Camera& camera,
                                     const vision::Target& target)
    : spec_(std::move(spec)),
      camera_json_(camera_json(camera)),
      target_json_(target_json(target)),
      width_px_(camera.width_px()),
      height_px_(camera.height_px()) {}

ExternalEstimator::~ExternalEstimator() = default;

bool ExternalEstimator::running() const {
  return process_ != nullptr;
}

std::vector<LifeEvent> ExternalEstimator::take_events() {
  std::vector<LifeEvent> out;
  out.swap(events_);
  return out;
}

void ExternalEstimator::stop(std::chrono::milliseconds grace) {
  if (!process_) return;
  process_->child.stop(Clock::now() + grace);
  process_.reset();
}

std::optional<Failure> ExternalEstimator::start() {
  if (disabled_) return Failure{FailureKind::kDisabled, disabled_->reason};
  if (process_) return std::nullopt;
  if (auto f = launch()) {
    fail(*f);
    return f;
  }
  return std::nullopt;
}

std::optional<Failure> ExternalEstimator::launch() {
  ++starts_;
  try {
    process_ = std::make_unique<Process>(spec_.command, spec_.working_dir);
  } catch (const ChildError& e) {
    return Failure{FailureKind::kStart, e.what()};
  }
  return handshake();
}

std::optional<Failure> ExternalEstimator::handshake() {
  const auto deadline = Clock::now() + spec_.startup_timeout;
  std::string line;
  try {
    process_->child.write_all(protocol::hello_line(), deadline);
    line = process_->child.read_line(deadline, kMaxLineBytes);
  } catch (const ChildTimeout& e) {
    return Failure{FailureKind::kStart, std::string("handshake: ") + e.what() + " (" +
                                            std::to_string(spec_.startup_timeout.count()) +
                                            " ms, startup_timeout_ms)"};
  } catch (const ChildError& e) {
    return Failure{FailureKind::kStart, std::string("handshake: ") + e.what()};
  }
  if (auto f = protocol::check_hello(line, reported_name_, reported_version_)) return f;
  events_.push_back({"started " + spec_.command[0] + " (pid " +
                     std::to_string(process_->child.pid()) + "): " + reported_name_ + " " +
                     reported_version_ + ", protocol " + kProtocolName + " " +
                     std::to_string(kProtocolVersion)});
  return std::nullopt;
}

// Kills the process after a failure and applies the restart policy
// (external_estimator.hpp).
void ExternalEstimator::fail(const Failure& f) {
  if (process_) {
    process_->child.stop(Clock::now());
    process_.reset();
  }
  events_.push_back({std::string(to_string(f.kind)) + ": " + f.reason});
  if (f.kind == FailureKind::kProtocol) {
    disabled_ = f;
    events_.push_back({"disabled for the rest of the sweep: " + f.reason});
  } else if (restarts_ >= spec_.max_restarts) {
    disabled_ =
        Failure{FailureKind::kDisabled, "failed after " + std::to_string(restarts_) +
                                            " restarts (max_restarts); last: " + to_string(f.kind) +
                                            ": " + f.reason};
    events_.push_back({"disabled for the rest of the sweep: " + disabled_->reason});
  }
}

std::optional<Failure> ExternalEstimator::ensure_running() {
  if (disabled_) return Failure{FailureKind::kDisabled, disabled_->reason};
  if (process_) return std::nullopt;
  if (starts_ > 0) {
    ++restarts_;
    events_.push_back({"restart " + std::to_string(restarts_) + " of at most " +
                       std::to_string(spec_.max_restarts)});
  }
  if (auto f = launch()) {
    fail(*f);
    return f;
  }
  return std::nullopt;
}

FrameResult ExternalEstimator::estimate(const FrameRequest& request) {
  if (auto f = ensure_running()) {
    FrameResult r;
    r.failure = f;
    return r;
  }
  FrameResult r = exchange(request);
  if (r.failure && r.failure->kind != FailureKind::kDeclined)
    fail(*r.failure);
  else if (r.failure)
    events_.push_back({std::string("declined: ") + r.failure->reason});
  return r;
}

FrameResult ExternalEstimator::exchange(const FrameRequest& request) {
  FrameResult r;
  const std::int64_t id = next_frame_id_++;
  const std::string line = protocol::frame_line(id, request, width_px_, height_px_, camera_json_,
                                                target_json_, spec_.send_corners);
  const auto start = Clock::now();
  const auto deadline = start + spec_.timeout;
  std::string answer;
  try {
    process_->child.write_all(line, deadline);
    answer = process_->child.read_line(deadline, kMaxLineBytes);
  } catch (const ChildTimeout& e) {
    r.failure = Failure{FailureKind::kTimeout, "frame " + std::to_string(id) + ": " + e.what() +
                                                   " (" + std::to_string(spec_.timeout.count()) +
                                                   " ms, timeout_ms)"};
    return r;
  } catch (const ChildError& e) {
    r.failure = Failure{FailureKind::kCrash, "frame " + std::to_string(id) + ": " + e.what()};
    return r;
  }
  protocol::read_result(answer, id, r);
  if (r.failure) r.failure->reason = "frame " + std::to_string(id) + ": " + r.failure->reason;
  r.round_trip_us = vision::seconds_since(start) * 1e6;
  return r;
}

}  // namespace rig::estimator
