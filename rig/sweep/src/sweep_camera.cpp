#include "rig/sweep/sweep_camera.hpp"

#include <string>
#include <thread>

namespace rig::sweep {

bool camera_may_be_held(const vision::CaptureError& error) {
  return dynamic_cast<const vision::CaptureTimeout*>(&error) != nullptr ||
         dynamic_cast<const vision::CaptureControlLost*>(&error) != nullptr ||
         std::string(error.what()).find(" refused") != std::string::npos;
}

void check_camera_frame(vision::FrameSource& camera, const SweepConfig& config) {
  camera.trigger();
  const vision::Frame frame = camera.grab(config.grab_timeout);
  if (const auto mismatch = config.camera.image_size_mismatch(
          frame.image.size(), "a frame of camera " + config.camera_spec,
          config.calibration_description()))
    throw SweepConfigError(config.sweep_file + ": capture.calibration: " + *mismatch +
                           "; expected the calibration of this camera at this resolution");
}

std::unique_ptr<vision::FrameSource> open_sweep_camera(const SweepConfig& config,
                                                       const FrameSourceFactory& make,
                                                       const HeldCameraPolicy& policy,
                                                       const CameraRetryObserver& on_retry) {
  const auto deadline = std::chrono::steady_clock::now() + policy.patience;
  for (int attempt = 1;; ++attempt) {
    std::unique_ptr<vision::FrameSource> camera = make();
    try {
      camera->open();
      check_camera_frame(*camera, config);
      return camera;
    } catch (const vision::CaptureError& e) {
      if (!camera_may_be_held(e) || std::chrono::steady_clock::now() > deadline) throw;
      if (on_retry) on_retry(attempt, e);
    }
    camera.reset();  // let go of the camera before asking it again
    std::this_thread::sleep_for(policy.interval);
  }
}

std::unique_ptr<vision::FrameSource> open_sweep_camera(const SweepConfig& config,
                                                       const CameraRetryObserver& on_retry) {
  return open_sweep_camera(
      config, [&config] { return vision::make_frame_source(config.camera_spec, config.capture); },
      HeldCameraPolicy{}, on_retry);
}

}  // namespace rig::sweep
