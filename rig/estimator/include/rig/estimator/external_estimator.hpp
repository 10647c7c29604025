// rig::estimator: pose estimators outside rig, as processes that rig starts
// once per sweep and talks to in JSON lines over their stdin and stdout. The
// protocol ("rig-estimator", version 1) is documented field by field in
// docs/external-estimators.md; this header is its client.
//
// Containment. Whatever the process does, the sweep goes on: a crash, a
// frame not answered within timeout_ms, a line that is not a valid answer, or
// a handshake naming another protocol or version makes that frame the
// estimator's failure (FrameResult::failure, with the reason), and the
// process is killed. The next frame starts it again, at most max_restarts
// times per sweep; after that, or at once after a wrong protocol or version
// (restarting cannot fix it), the estimator is disabled for the rest of the
// sweep and every later frame is a failure naming why.
#pragma once

#include <Eigen/Core>
#include <array>
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vision/camera.hpp"
#include "vision/detector.hpp"
#include "vision/pose.hpp"
#include "vision/target.hpp"

namespace rig::estimator {

inline constexpr const char* kProtocolName = "rig-estimator";
inline constexpr int kProtocolVersion = 1;
// The longest line rig reads from an estimator (a result with a few hundred
// poses and corners is tens of kB): a longer one is malformed output.
inline constexpr std::size_t kMaxLineBytes = std::size_t{1} << 20;

// One external estimator as the sweep file's [[estimator]] configures it.
struct EstimatorSpec {
  std::string name;                  // [A-Za-z0-9_.-]{1,64}; stored as solver "ext:NAME"
  std::vector<std::string> command;  // argv, argv[0] looked up on PATH; no shell
  // The folder it runs in (the sweep file's folder), "" = rig's own. Image
  // paths rig sends are absolute.
  std::string working_dir;
  std::chrono::milliseconds timeout{2000};           // per frame, from request to answer
  std::chrono::milliseconds startup_timeout{10000};  // start to handshake answer
  int max_restarts = 3;                              // per sweep, after failures; then disabled
  bool send_corners = true;                          // send rig's detected corners with each frame
  std::string solver_name() const { return "ext:" + name; }
};

// One pose an estimator returned for a frame.
struct ExternalPose {
  // "target" (all markers) or a marker id as decimal text, as rig's solvers'
  // scopes; "target" when the estimator does not say.
  std::string scope = "target";
  vision::Pose T_cam_target;  // target frame in the camera frame, metres
  // The estimator's own corners per marker id, distorted pixels (A, B, C, D),
  // when it sent them.
  std::vector<std::pair<int, std::array<Eigen::Vector2d, 4>>> corners_px;
};

// Why a frame has no answer from the estimator. The kind is short and stable
// (it is the failure's termination in the database, what reports group by);
// the reason says what happened.
enum class FailureKind {
  kStart,      // "start": the program could not be started or handshake failed
  kProtocol,   // "protocol": wrong protocol name or version (disables at once)
  kCrash,      // "crash": it exited or closed its stdout
  kTimeout,    // "timeout": no answer within timeout_ms
  kMalformed,  // "malformed": an answer that is not the protocol's
  kDeclined,   // "declined": it answered with an error of its own
  kDisabled,   // "disabled": restarts used up earlier in the sweep
};
const char* to_string(FailureKind kind);

struct Failure {
  FailureKind kind;
  std::string reason;
};

struct FrameResult {
  std::vector<ExternalPose> poses;  // zero or more; empty with no failure = no pose found
  std::optional<Failure> failure;
  // The estimator's own processing time, microseconds, as it reported it;
  // absent when it did not say or failed.
  std::optional<double> estimator_time_us;
  double round_trip_us = 0;  // request written to answer parsed, microseconds
};

// What rig sends about one frame.
struct FrameRequest {
  std::string image_path;  // a lossless PNG of the frame, as the camera delivered it
  // rig's detections on the frame (sent when spec.send_corners); may be null.
  const std::vector<vision::Detection>* detections = nullptr;
};

// Something an estimator's life produced that the run log keeps: started
// (with its name and version), failed, restarted, disabled.
struct LifeEvent {
  std::string message;
};

class ExternalEstimator {
 public:
  // Nothing is started yet. camera and target are sent with every frame.
  ExternalEstimator(EstimatorSpec spec, const vision::Camera& camera, const vision::Target& target);
  ~ExternalEstimator();
  ExternalEstimator(const ExternalEstimator&) = delete;
  ExternalEstimator& operator=(const ExternalEstimator&) = delete;

  const EstimatorSpec& spec() const { return spec_; }

  // Starts the process and shakes hands (startup_timeout). On failure the
  // estimator is not running; the failure is returned and counted as the
  // first frame's would be. Never throws for anything the process does.
  std::optional<Failure> start();

  // Sends one frame and reads its answer (timeout). Starts (or restarts,
  // within max_restarts) the process first when it is not running. Never
  // throws for anything the process does.
  FrameResult estimate(const FrameRequest& request);

  // Closes its stdin and waits up to `grace` for it to exit, then kills it.
  void stop(std::chrono::milliseconds grace = std::chrono::milliseconds(1000));

  bool running() const;
  bool disabled() const { return disabled_.has_value(); }
  // The handshake's {name, version} of the running (or last) process.
  const std::string& reported_name() const { return reported_name_; }
  const std::string& reported_version() const { return reported_version_; }
  int restarts() const { return restarts_; }

  // The events since the last call, oldest first.
  std::vector<LifeEvent> take_events();

 private:
  struct Process;
  std::optional<Failure> launch();
  std::optional<Failure> handshake();
  std::optional<Failure> ensure_running();
  void fail(const Failure& f);
  FrameResult exchange(const FrameRequest& request);

  EstimatorSpec spec_;
  std::string camera_json_, target_json_;  // sent with every frame, serialised once
  int width_px_ = 0, height_px_ = 0;
  std::unique_ptr<Process> process_;
  std::int64_t next_frame_id_ = 0;
  int starts_ = 0;
  int restarts_ = 0;
  std::optional<Failure> disabled_;
  std::string reported_name_, reported_version_;
  std::vector<LifeEvent> events_;
};

// The request and answer JSON of protocol version 1, exposed for tests and
// the documentation's examples.
std::string camera_json(const vision::Camera& camera);
std::string target_json(const vision::Target& target);

}  // namespace rig::estimator
