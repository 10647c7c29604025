// vision::V4l2Source: a V4L2 capture device (USB/UVC cameras, frame grabbers)
// through the kernel's ioctl API, memory-mapped streaming I/O.
//
// V4L2 has no software trigger: the device streams continuously. trigger()
// records the host's CLOCK_MONOTONIC time and the next grab() drops (counts
// as discarded) every frame whose exposure timestamp precedes it, so the frame
// returned was exposed after the trigger (after the bench settled). Devices
// whose timestamps are not CLOCK_MONOTONIC cannot be compared: the next frame
// is taken.
//
// Pixel formats: GREY (8 bit), Y16 (16 bit), YUYV (its luma is kept) and MJPG
// (decoded to grey); the device is asked for GREY and its answer decides. The
// conversion is vision::v4l2_buffer_to_image (vision/pixel_format.hpp),
// tested on buffers; the ioctl path itself needs a device (none in CI).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "vision/frame_source.hpp"

namespace vision {

class V4l2Source final : public FrameSource {
 public:
  V4l2Source(std::string path, CaptureOptions options = {});
  ~V4l2Source() override;

  // Opens the device, checks that it is a streaming video capture device,
  // sets the format (options.width/height when given) and starts streaming.
  // Throws CaptureError naming the path when it is missing, not a V4L2 device
  // (e.g. /dev/null, a regular file), not a capture device, or refuses a step.
  void open() override;
  void trigger() override;
  Frame grab(std::chrono::milliseconds timeout) override;
  void close() override;

  std::string name() const override { return "v4l2:" + path_; }
  // After open(): the driver (vendor), card (model), bus (serial) and driver
  // version VIDIOC_QUERYCAP reports.
  CameraIdentity identity() const override { return identity_; }
  CaptureCounters counters() const override { return counters_; }

 private:
  struct Mapping {
    void* start = nullptr;
    size_t length = 0;
  };
  std::string path_;
  CaptureOptions options_;
  CaptureCounters counters_;
  CameraIdentity identity_;
  int fd_ = -1;
  bool streaming_ = false;
  std::vector<Mapping> buffers_;
  uint32_t fourcc_ = 0;
  int width_ = 0, height_ = 0, bytes_per_line_ = 0;
  uint64_t not_before_ns_ = 0;  // CLOCK_MONOTONIC of the last trigger()
};

}  // namespace vision
