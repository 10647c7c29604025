// vision::GigeSource: a GigE Vision camera through Aravis 0.8.
//
// Opening by IPv4 address talks to the camera directly (milliseconds);
// opening by device id ("Vendor-Model-Serial", as `arv-tool-0.8` lists it)
// runs Aravis's discovery first (about 1 s on loopback).
//
// Every buffer's status is checked: only ARV_BUFFER_STATUS_SUCCESS becomes a
// Frame. Other statuses (missing packets, packet timeout, size mismatch...)
// count as incomplete; gaps in the camera's frame ids count as lost (a frame
// whose leader packet was lost has no id: it counts as incomplete and fills
// one place of the gap its id leaves). In
// software trigger mode an incomplete frame or a timeout is retried by
// triggering again, up to CaptureOptions::retries times.
//
// The stream uses a fixed receive socket buffer (CaptureOptions::
// socket_buffer_bytes): with Aravis's automatic size an unpaced camera on
// loopback loses most frames as soon as the other core is busy.
//
// Aravis objects are used from the calling thread only; Aravis's stream
// thread fills the buffers. Not thread-safe: one thread drives a source.
#pragma once

#include <memory>
#include <string>

#include "vision/camera_clock.hpp"
#include "vision/frame_source.hpp"

namespace vision {

class GigeSource final : public FrameSource {
 public:
  // `device` is an IPv4 address or an Aravis device id.
  GigeSource(std::string device, CaptureOptions options = {});
  ~GigeSource() override;

  // Connects, applies the options (pixel format, region, exposure, gain,
  // trigger mode), creates the stream and starts acquisition. Throws
  // CaptureError naming the device and the feature that was refused.
  void open() override;
  // Software trigger mode: drops any frame already queued (it was not asked
  // for) and sends TriggerSoftware. Free run: drops queued frames only.
  void trigger() override;
  // Throws CaptureControlLost once the camera has taken control away
  // (Aravis's heartbeat found this controller's privilege gone); the source
  // must then be closed and opened again.
  Frame grab(std::chrono::milliseconds timeout) override;
  void close() override;

  std::string name() const override { return "gige:" + device_; }
  CaptureCounters counters() const override { return counters_; }

  // After open(): the camera's device id as Aravis's discovery lists it
  // (vendor-model-serial).
  const std::string& device_id() const { return identity_.device_id; }
  CameraIdentity identity() const override { return identity_; }
  // After open(): whether the receiving thread got real-time scheduling
  // (CaptureOptions::realtime_receiver).
  bool realtime_receiver() const;
  // How camera timestamps map to host time (vision/camera_clock.hpp): a latch
  // at open() when the camera has GevTimestampControlLatch, else the frames'
  // arrivals. Frame::exposure_host_time is camera_timestamp_ns mapped by it.
  const CameraClock& camera_clock() const { return clock_; }

 private:
  struct Impl;
  std::string device_;
  CaptureOptions options_;
  CaptureCounters counters_;
  CameraIdentity identity_;
  CameraClock clock_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vision
