// The camera of a sweep, opened and checked before anything moves
// (docs/data-flow.md): it answers, and its image is the size the sweep file's
// calibration was made at. A wrong calibration stops the sweep before the
// bench moves or the database is written.
#pragma once

#include <chrono>
#include <functional>
#include <memory>

#include "rig/sweep/sweep_config.hpp"
#include "vision/frame_source.hpp"

namespace rig::sweep {

// How long a sweep keeps asking a camera that may be held by a controller
// that died. A GigE Vision camera serves one controller at a time and keeps
// serving it until that controller's heartbeat stops for the camera's
// heartbeat timeout (GigE Vision bootstrap register "Heartbeat Timeout",
// 0x0938: 3 s by default, often set longer on slow links). A controller
// killed with -9, or whose host lost power, never releases the camera: until
// the timeout expires the camera refuses a new controller or sends it nothing.
struct HeldCameraPolicy {
  // 15 s: five default heartbeat timeouts, so that a camera configured for a
  // few times the default is still waited out; a camera that still refuses
  // after that is held by a live controller, and waiting longer would only
  // delay the message.
  std::chrono::milliseconds patience{15000};
  // Between attempts: takes the camera within half a second of its release
  // without flooding its control channel.
  std::chrono::milliseconds interval{500};
};

// Whether a failure to open or read a camera may be a camera held by another
// controller, worth asking again: no frame in time (vision::CaptureTimeout),
// a camera that answers but refuses a setting (" refused" in the message,
// vision::GigeSource), or one that took control away again right after
// granting it (vision::CaptureControlLost: the camera missed this
// controller's heartbeats for its timeout, on a host or camera that stalled
// while loaded). A camera that does not answer at all is absent.
bool camera_may_be_held(const vision::CaptureError& error);

// One frame before anything moves: triggers and grabs one frame of an open
// `camera` (config.faults.grab_timeout) and checks its size against
// config.camera. Throws vision::CaptureError from the camera, and
// SweepConfigError naming the sweep file, capture.calibration, the
// calibration's size and the camera's when they differ
// (vision::Camera::image_size_mismatch).
void check_camera_frame(vision::FrameSource& camera, const SweepConfig& config);

// Makes a new, unopened frame source for one attempt.
using FrameSourceFactory = std::function<std::unique_ptr<vision::FrameSource>()>;
// Told of an attempt that failed and will be made again: its number (1, 2,
// ...) and why it failed.
using CameraRetryObserver = std::function<void(int attempt, const vision::CaptureError& error)>;

// Opens a camera made by `make` and checks one frame (check_camera_frame).
// A failure for which camera_may_be_held is true is tried again with a new
// source every policy.interval until policy.patience has passed since the
// first attempt; `on_retry` (may be empty) hears of each. Returns the open,
// checked camera. Throws the last vision::CaptureError when the camera is
// absent or still failing after the patience; SweepConfigError from the size
// check at once.
std::unique_ptr<vision::FrameSource> open_sweep_camera(const SweepConfig& config,
                                                       const FrameSourceFactory& make,
                                                       const HeldCameraPolicy& policy,
                                                       const CameraRetryObserver& on_retry);

// The same for the sweep file's camera (vision::make_frame_source with
// config.camera_spec and config.capture) under the default policy. Also
// throws std::invalid_argument for a camera spec make_frame_source does not
// know.
std::unique_ptr<vision::FrameSource> open_sweep_camera(const SweepConfig& config,
                                                       const CameraRetryObserver& on_retry);

}  // namespace rig::sweep
