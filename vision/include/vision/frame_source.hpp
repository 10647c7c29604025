// vision::FrameSource: one interface over every camera the rig can trigger
// (GigE Vision through Aravis, V4L2) and over recorded frames (a folder of
// images), so that the controller never knows which one it talks to (the
// libmodbus idea: one core, transports as backends).
//
// Contract. open() acquires the device and starts acquisition. In software
// trigger mode, trigger() asks for exactly one exposure and the next grab()
// returns that exposure's frame, whole: a frame the transport delivered
// incomplete is counted and never returned. Sources without a trigger (V4L2,
// replay, a free-running GigE camera) treat trigger() as "the next frame must
// start after now". close() releases the device; the destructor closes.
//
// Errors. CaptureError names the device and what failed (absent device, a
// device that is not a camera, a transport failure, a frame still incomplete
// after the configured retries). CaptureTimeout is the CaptureError of a grab
// that saw no frame within its timeout; CaptureControlLost that of a camera
// that took its control away from this source. All are thrown where the
// cause is known; counters() tells how many frames went wrong on the way.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <stdexcept>
#include <string>

namespace vision {

// A capture failure. device() is the spec or path of the source (e.g.
// "gige:127.0.0.1", "v4l2:/dev/video0"), also part of what().
class CaptureError : public std::runtime_error {
 public:
  CaptureError(const std::string& device, const std::string& message)
      : std::runtime_error(device + ": " + message), device_(device) {}
  const std::string& device() const { return device_; }

 private:
  std::string device_;
};

// No frame within the timeout of grab() (after the configured retries).
class CaptureTimeout : public CaptureError {
 public:
  using CaptureError::CaptureError;
};

// The camera took control away from this source: it stopped hearing the
// source's heartbeat for its heartbeat timeout (a host or camera that stalled
// that long, a link that dropped the heartbeats) or handed control to another
// application. The camera still answers; a new source may take it again.
class CaptureControlLost : public CaptureError {
 public:
  using CaptureError::CaptureError;
};

// A replay source has delivered its last frame.
class EndOfFrames : public CaptureError {
 public:
  using CaptureError::CaptureError;
};

// One whole frame. The image owns its pixels (copied out of the transport's
// buffer), so a Frame outlives the source.
struct Frame {
  // CV_8UC1 (Mono8, BayerRG8 demosaiced to luminance, V4L2 GREY/YUYV/MJPG) or
  // CV_16UC1 (Mono10/12/12Packed/16, V4L2 Y16), LSB-aligned: the conversions
  // of vision/pixel_format.hpp.
  cv::Mat image;
  // Bits per pixel the camera measured (8, 10, 12 or 16): Mono10 fills
  // 0 .. 1023 of a CV_16UC1 image.
  int significant_bits = 8;
  // The device's frame counter (GigE block id: 16 bits on GigE Vision 1.x and
  // never 0; V4L2 sequence), or the index in a replay.
  uint64_t frame_id = 0;
  // The device's timestamp of the exposure, ns on the device clock (GigE: the
  // camera's tick counter scaled to ns; V4L2: CLOCK_MONOTONIC). 0 if unknown.
  uint64_t camera_timestamp_ns = 0;
  // When the host had the whole frame (wall clock).
  std::chrono::system_clock::time_point host_time{};
  // The start of the exposure on the host's wall clock: camera_timestamp_ns
  // mapped by the source's camera clock (GigE: vision/camera_clock.hpp, by
  // latch or by arrival). Unset when the source cannot tell (V4L2, replay).
  std::optional<std::chrono::system_clock::time_point> exposure_host_time;
  // Where it came from: the source spec, and for a replay the file path.
  std::string origin;
};

// What went wrong so far, since open(). Monotonic counts.
struct CaptureCounters {
  uint64_t delivered = 0;   // frames returned by grab()
  uint64_t incomplete = 0;  // frames the transport delivered with missing or bad data
  uint64_t lost = 0;        // frames the device sent that never arrived (frame id gaps)
  uint64_t timeouts = 0;    // waits that ended without a frame
  uint64_t retries = 0;     // triggers or waits repeated after an incomplete frame or a timeout
  uint64_t discarded = 0;   // whole frames dropped because they were not the one asked for
};

// How a camera identifies itself (GenICam DeviceVendorName, DeviceModelName,
// DeviceSerialNumber, DeviceVersion; V4L2: driver, card, bus, driver
// version). "" where the device does not say.
struct CameraIdentity {
  std::string device_id;  // GigE: vendor-model-serial as Aravis's discovery lists it
  std::string vendor, model, serial, device_version;
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  FrameSource() = default;
  FrameSource(const FrameSource&) = delete;
  FrameSource& operator=(const FrameSource&) = delete;

  // Acquires the device and starts acquisition. Throws CaptureError naming the
  // device when it is absent, busy, or not a camera. Calling open() on an open
  // source is a no-op.
  virtual void open() = 0;
  // Asks for one exposure starting now (see the contract above).
  // Precondition: open(). Throws CaptureError if the device refuses.
  virtual void trigger() = 0;
  // Waits up to `timeout` for the next whole frame. Precondition: open().
  // Throws CaptureTimeout, CaptureError, or EndOfFrames (replay).
  virtual Frame grab(std::chrono::milliseconds timeout) = 0;
  // Stops acquisition and releases the device; safe to call twice.
  virtual void close() = 0;

  // The spec this source was made from, e.g. "gige:127.0.0.1".
  virtual std::string name() const = 0;
  virtual CaptureCounters counters() const = 0;
  // After open(): what the device says it is; every field "" for sources that
  // are no device (a replay) and before open().
  virtual CameraIdentity identity() const { return {}; }
};

// How a camera is driven; every field documents its default.
struct CaptureOptions {
  // Software trigger: one exposure per trigger() (what a sweep needs: the frame
  // is taken after the bench settled). Free run: the camera streams at its
  // frame rate and grab() takes the next frame; cheaper latency, but a frame
  // may straddle a move.
  bool software_trigger = true;
  // GenICam pixel format name: Mono8, Mono10, Mono12, Mono12Packed, Mono16 or
  // BayerRG8 (vision/pixel_format.hpp says how each becomes Frame::image).
  std::string pixel_format = "Mono8";
  // Region of interest in pixels; unset keeps the camera's current value.
  std::optional<int> width, height, offset_x, offset_y;
  // Exposure time in µs and analog gain (camera units, usually dB); unset
  // keeps the camera's value. Longer exposure: less noise, more motion blur.
  std::optional<double> exposure_us, gain;
  // Free-run frame rate in Hz; unset keeps the camera's value.
  std::optional<double> frame_rate_hz;
  // How many times a grab re-triggers (or waits again) after an incomplete
  // frame or a timeout before it throws. More retries ride out a flaky link
  // at the cost of a longer worst-case grab.
  int retries = 2;
  // GigE: stream packet size in bytes (GenICam GevSCPSPacketSize: the UDP
  // payload of one GVSP packet plus its 36 bytes of IP, UDP and GVSP
  // headers); unset keeps the camera's value. 576 .. 9000: up to 1500 on a
  // standard Ethernet MTU, larger only with jumbo frames on every hop. Larger
  // packets mean fewer packets (and interrupts) per frame.
  std::optional<int> packet_size_bytes;
  // GigE: inter-packet delay (GevSCPD) in ns, 0 .. 1e8; unset keeps the
  // camera's value. Converted by Aravis to the camera's timestamp ticks.
  // Paces a camera that floods a slow link or a switch shared by several
  // cameras; each packet then takes this much longer, so a frame of P packets
  // takes about P x delay longer.
  std::optional<double> inter_packet_delay_ns;
  // GigE: receive socket buffer, bytes, fixed (not Aravis's automatic size,
  // which follows the payload). A few MB holds several frames, so frames are
  // not lost while the receiving thread is descheduled by a busy core; the
  // kernel caps it at net.core.rmem_max (4 MiB on Debian 12).
  int socket_buffer_bytes = 4 * 1024 * 1024;
  // GigE: buffers queued for the stream; more absorb bursts in free run.
  int n_buffers = 8;
  // GigE: ask the camera to resend missing packets (GVSP resend). Off makes a
  // lost packet an incomplete frame at once.
  bool packet_resend = true;
  // GigE: how long, in ms, a partly received frame waits for its missing
  // packets (and their resends) before it is given up as incomplete. Aravis's
  // 100 ms is shorter than the time a receiving thread can be descheduled on a
  // loaded 2-core host, which then closes frames whose packets are waiting in
  // the socket buffer; longer reports a truly broken link later.
  int frame_retention_ms = 1000;
  // GigE: run the stream's receiving thread under SCHED_FIFO (priority 10)
  // when the process may (root, CAP_SYS_NICE or an RLIMIT_RTPRIO), so that a
  // busy host cannot starve it while the camera keeps sending; otherwise it
  // stays at normal priority (GigeSource::realtime_receiver() tells which).
  // The thread sleeps in poll() between packets, so it cannot monopolize a core.
  bool realtime_receiver = true;
};

// Makes a source from a spec:
//   gige:ID        an Aravis device id, e.g. gige:Aravis-Fake-GV01 (discovery, ~1 s)
//   gige:ADDRESS   an IPv4 address, e.g. gige:127.0.0.1 (direct, milliseconds)
//   v4l2:PATH      a V4L2 capture device, e.g. v4l2:/dev/video0
//   replay:DIR     the images of a folder in name order, e.g. replay:runs/7/frames
// The source is not opened yet. Throws std::invalid_argument naming the spec
// and the accepted forms when the scheme is unknown or the rest is empty.
std::unique_ptr<FrameSource> make_frame_source(const std::string& spec,
                                               const CaptureOptions& options = {});

}  // namespace vision
