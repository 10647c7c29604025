#include "vision/gige_source.hpp"

#include <arv.h>
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <utility>

#include "vision/pixel_format.hpp"

namespace vision {
namespace {

// Takes ownership of a GError and returns its message ("" for none).
std::string take_message(GError* error) {
  if (error == nullptr) return "";
  std::string message = error->message != nullptr ? error->message : "unknown error";
  g_error_free(error);
  return message;
}

const char* status_name(ArvBufferStatus status) {
  switch (status) {
    case ARV_BUFFER_STATUS_SUCCESS:
      return "success";
    case ARV_BUFFER_STATUS_CLEARED:
      return "cleared";
    case ARV_BUFFER_STATUS_TIMEOUT:
      return "packet timeout";
    case ARV_BUFFER_STATUS_MISSING_PACKETS:
      return "missing packets";
    case ARV_BUFFER_STATUS_WRONG_PACKET_ID:
      return "wrong packet id";
    case ARV_BUFFER_STATUS_SIZE_MISMATCH:
      return "size mismatch";
    case ARV_BUFFER_STATUS_FILLING:
      return "still filling";
    case ARV_BUFFER_STATUS_ABORTED:
      return "aborted";
    default:
      return "unknown";
  }
}

// ArvStreamCallback: runs on Aravis's stream thread; at its start, asks for
// real-time scheduling if the options want it.
void on_stream_event(void* user_data, ArvStreamCallbackType type, ArvBuffer* /*buffer*/) {
  if (type != ARV_STREAM_CALLBACK_TYPE_INIT) return;
  auto* realtime = static_cast<std::atomic<int>*>(user_data);
  if (realtime->load() == 0) return;
  sched_param param{};
  param.sched_priority = 10;
  realtime->store(pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0 ? 2 : 1);
}

void on_control_lost(ArvDevice* /*device*/, gpointer flag) {
  static_cast<std::atomic<bool>*>(flag)->store(true);
}

// What to do about a camera another application controls.
constexpr const char* kHeldByAnother =
    "most likely another rig sweep or rig capture (or arv-viewer) is using it. Stop that one; "
    "a controller that died releases the camera once its heartbeat times out (a few seconds)";

// Throws CaptureError, taking `error`, when the camera refused `what`. A
// write that times out on a camera that answered discovery is most often a
// camera another application controls.
void check(GError* error, const std::string& who, const std::string& what) {
  if (error == nullptr) return;
  const std::string message = take_message(error);
  const bool timeout = message.find("timeout") != std::string::npos;
  throw CaptureError(who, what + " refused: " + message +
                              (timeout ? std::string(" (the camera did not answer the write: ") +
                                             kHeldByAnother + ")"
                                       : std::string()));
}

// The GenICam Device* features; the id as Aravis's discovery lists it:
// vendor-model-serial. A feature the camera lacks reads as "".
CameraIdentity identity_of(ArvCamera* camera) {
  auto text = [](const char* value) { return std::string(value ? value : ""); };
  CameraIdentity id;
  id.vendor = text(arv_camera_get_vendor_name(camera, nullptr));
  id.model = text(arv_camera_get_model_name(camera, nullptr));
  id.serial = text(arv_camera_get_device_serial_number(camera, nullptr));
  GError* error = nullptr;
  const char* version =
      arv_device_get_string_feature_value(arv_camera_get_device(camera), "DeviceVersion", &error);
  if (error != nullptr)
    g_clear_error(&error);
  else
    id.device_version = text(version);
  id.device_id = id.vendor + "-" + id.model + "-" + id.serial;
  return id;
}

// The region of interest the options ask for, the camera's own where they
// leave a value out.
void set_region(ArvCamera* camera, const CaptureOptions& o, const std::string& who) {
  GError* error = nullptr;
  gint x = 0, y = 0, w = 0, h = 0;
  arv_camera_get_region(camera, &x, &y, &w, &h, &error);
  check(error, who, "reading the region");
  arv_camera_set_region(camera, o.offset_x.value_or(x), o.offset_y.value_or(y), o.width.value_or(w),
                        o.height.value_or(h), &error);
  check(error, who,
        "region " + std::to_string(o.width.value_or(w)) + "x" +
            std::to_string(o.height.value_or(h)) + "+" + std::to_string(o.offset_x.value_or(x)) +
            "+" + std::to_string(o.offset_y.value_or(y)));
}

// The exposure time in µs, by the feature the camera has: SFNC's
// ExposureTime (GenICam SFNC 2.x) or the older ExposureTimeAbs (SFNC 1.x,
// still the name on many GigE Vision 1.x cameras). Both are floats in µs.
void set_exposure(ArvCamera* camera, double exposure_us, const std::string& who) {
  GError* error = nullptr;
  ArvDevice* device = arv_camera_get_device(camera);
  const char* feature = nullptr;
  for (const char* name : {"ExposureTime", "ExposureTimeAbs"}) {
    if (arv_device_is_feature_available(device, name, &error)) {
      feature = name;
      break;
    }
    g_clear_error(&error);
  }
  if (feature == nullptr)
    throw CaptureError(who, "exposure time " + std::to_string(exposure_us) +
                                " us: the camera has neither ExposureTime nor ExposureTimeAbs");
  arv_device_set_float_feature_value(device, feature, exposure_us, &error);
  check(error, who, std::string(feature) + "=" + std::to_string(exposure_us) + " us");
}

// Applies the options' features: continuous acquisition, pixel format,
// region, exposure, gain, and software trigger or free run at a frame rate.
void configure(ArvCamera* camera, const CaptureOptions& o, const std::string& who) {
  GError* error = nullptr;
  arv_camera_set_acquisition_mode(camera, ARV_ACQUISITION_MODE_CONTINUOUS, &error);
  check(error, who, "AcquisitionMode=Continuous");
  arv_camera_set_pixel_format_from_string(camera, o.pixel_format.c_str(), &error);
  check(error, who, "PixelFormat=" + o.pixel_format);
  if (o.width || o.height || o.offset_x || o.offset_y) set_region(camera, o, who);
  if (o.exposure_us) set_exposure(camera, *o.exposure_us, who);
  if (o.gain) {
    arv_camera_set_gain(camera, *o.gain, &error);
    check(error, who, "gain " + std::to_string(*o.gain));
  }
  if (o.packet_size_bytes) {
    arv_camera_gv_set_packet_size(camera, *o.packet_size_bytes, &error);
    check(error, who, "GevSCPSPacketSize=" + std::to_string(*o.packet_size_bytes) + " bytes");
  }
  if (o.inter_packet_delay_ns) {
    arv_camera_gv_set_packet_delay(camera, static_cast<gint64>(*o.inter_packet_delay_ns), &error);
    check(error, who,
          "inter-packet delay (GevSCPD) " + std::to_string(*o.inter_packet_delay_ns) + " ns");
  }
  if (o.software_trigger) {
    arv_camera_set_trigger(camera, "Software", &error);
    check(error, who, "software trigger (TriggerMode=On, TriggerSource=Software)");
  } else {
    arv_camera_clear_triggers(camera, &error);
    check(error, who, "free run (TriggerMode=Off)");
    if (o.frame_rate_hz) {
      arv_camera_set_frame_rate(camera, *o.frame_rate_hz, &error);
      check(error, who, "frame rate " + std::to_string(*o.frame_rate_hz) + " Hz");
    }
  }
}

// Host CLOCK_REALTIME, ns since the epoch.
int64_t host_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// Latches the camera's timestamp counter (GevTimestampControlLatch, then
// GevTimestampValue) between two reads of the host clock, three times (the
// narrowest bracket wins: vision/camera_clock.hpp). A camera without the
// latch, or one that refuses it, leaves the clock to the frames' arrivals.
void latch_clock(ArvCamera* camera, CameraClock* clock) {
  ArvDevice* device = arv_camera_get_device(camera);
  GError* error = nullptr;
  const bool has_latch =
      arv_device_is_feature_available(device, "GevTimestampControlLatch", &error) &&
      arv_device_is_feature_available(device, "GevTimestampValue", &error);
  const guint64 hz = has_latch && error == nullptr
                         ? arv_gv_device_get_timestamp_tick_frequency(ARV_GV_DEVICE(device), &error)
                         : 0;
  if (error != nullptr || hz == 0) {
    g_clear_error(&error);
    return;
  }
  const double ns_per_tick = 1e9 / static_cast<double>(hz);
  for (int k = 0; k < 3; ++k) {
    const int64_t before = host_now_ns();
    arv_device_execute_command(device, "GevTimestampControlLatch", &error);
    const gint64 ticks =
        error == nullptr ? arv_device_get_integer_feature_value(device, "GevTimestampValue", &error)
                         : 0;
    const int64_t after = host_now_ns();
    if (error != nullptr) {
      g_clear_error(&error);
      return;
    }
    clock->add_latch(before, static_cast<int64_t>(static_cast<double>(ticks) * ns_per_tick), after,
                     static_cast<int64_t>(std::ceil(ns_per_tick)));
  }
}

// A buffer's image, or why there is none: a status other than success, a
// format the capture path does not read, or too few bytes for its format.
struct Payload {
  cv::Mat image;
  ArvPixelFormat format = 0;
  bool unreadable_format = false;
  std::string problem;
};

Payload payload_of(ArvBuffer* buffer) {
  Payload p;
  const ArvBufferStatus status = arv_buffer_get_status(buffer);
  size_t size = 0;
  const void* data =
      status == ARV_BUFFER_STATUS_SUCCESS ? arv_buffer_get_image_data(buffer, &size) : nullptr;
  if (data == nullptr) {
    p.problem = status_name(status);
    return p;
  }
  p.format = arv_buffer_get_image_pixel_format(buffer);
  if (!is_readable_pixel_format(p.format)) {
    p.unreadable_format = true;
    return p;
  }
  try {
    p.image = gige_payload_to_image(data, size, arv_buffer_get_image_width(buffer),
                                    arv_buffer_get_image_height(buffer), p.format);
  } catch (const PixelFormatError& e) {
    p.problem = e.what();  // a readable format, but not all of its bytes
  }
  return p;
}

std::chrono::system_clock::time_point wall_time(int64_t ns_since_epoch) {
  return std::chrono::system_clock::time_point(
      std::chrono::duration_cast<std::chrono::system_clock::duration>(
          std::chrono::nanoseconds(ns_since_epoch)));
}

// The Frame of a whole buffer; its timestamps feed the camera clock.
Frame frame_of(ArvBuffer* buffer, const Payload& payload, CameraClock* clock) {
  Frame frame;
  frame.image = payload.image;
  frame.significant_bits = significant_bits(payload.format);
  frame.frame_id = arv_buffer_get_frame_id(buffer);
  frame.camera_timestamp_ns = arv_buffer_get_timestamp(buffer);
  const auto arrival_ns = static_cast<int64_t>(arv_buffer_get_system_timestamp(buffer));
  frame.host_time = wall_time(arrival_ns);
  if (frame.camera_timestamp_ns != 0) {
    const auto camera_ns = static_cast<int64_t>(frame.camera_timestamp_ns);
    clock->add_arrival(camera_ns, arrival_ns);
    frame.exposure_host_time = wall_time(*clock->to_host_ns(camera_ns));
  }
  return frame;
}

}  // namespace

struct GigeSource::Impl {
  ArvCamera* camera = nullptr;
  ArvStream* stream = nullptr;
  gulong control_lost_handler = 0;
  std::atomic<bool> control_lost{false};
  // 0: not wanted, 1: wanted (or refused), 2: the stream thread runs SCHED_FIFO.
  std::atomic<int> realtime{0};
  // A trigger was sent and its frame has not been delivered yet: only then
  // does a grab that times out trigger again.
  bool trigger_pending = false;
  // The camera stopped answering control commands, or no longer takes them
  // from us (control lost): close() then does not wait for it to acknowledge
  // AcquisitionStop.
  bool unreachable = false;
  bool has_last_id = false;
  uint64_t last_id = 0;
  // Frames seen since last_id whose id is unknown (id 0, see note_frame_id).
  uint64_t without_id = 0;

  // Connects to `device`; throws CaptureError when no GigE Vision camera answers.
  void connect(const std::string& device, const std::string& who) {
    GError* error = nullptr;
    camera = arv_camera_new(device.c_str(), &error);
    if (camera == nullptr)
      throw CaptureError(who, "no GigE Vision camera answers at " + device + " (" +
                                  take_message(error) +
                                  "): is the camera powered and on this network, or, for the "
                                  "simulated rig, is `rig sim` running? `arv-tool-0.8` lists "
                                  "the cameras Aravis can see");
    if (!arv_camera_is_gv_device(camera)) {
      g_object_unref(camera);
      camera = nullptr;
      throw CaptureError(who, "device is not a GigE Vision camera");
    }
    // GigE Vision grants control to one application at a time; without it
    // every register write times out. "refused": a sweep asks again
    // (rig/sweep/sweep_camera.hpp), as a controller that died lets go.
    if (!arv_gv_device_is_controller(ARV_GV_DEVICE(arv_camera_get_device(camera)))) {
      g_object_unref(camera);
      camera = nullptr;
      throw CaptureError(who, std::string("control of the camera refused: it answers, but "
                                          "another process holds its control channel: ") +
                                  kHeldByAnother);
    }
  }

  // Creates the stream with the options' buffers and starts acquisition.
  void start_stream(const CaptureOptions& o, const std::string& who) {
    GError* error = nullptr;
    // The plain UDP socket, not Aravis's packet socket (which needs CAP_NET_RAW
    // and bypasses the socket buffer): the same path whoever runs the rig.
    arv_camera_gv_set_stream_options(camera, ARV_GV_STREAM_OPTION_PACKET_SOCKET_DISABLED);
    realtime = o.realtime_receiver ? 1 : 0;
    stream = arv_camera_create_stream(camera, on_stream_event, &realtime, &error);
    check(error, who, "creating the stream");
    g_object_set(
        stream, "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_FIXED, "socket-buffer-size",
        o.socket_buffer_bytes, "packet-resend",
        o.packet_resend ? ARV_GV_STREAM_PACKET_RESEND_ALWAYS : ARV_GV_STREAM_PACKET_RESEND_NEVER,
        "frame-retention", static_cast<guint>(o.frame_retention_ms) * 1000u, nullptr);
    const guint payload = arv_camera_get_payload(camera, &error);
    check(error, who, "reading PayloadSize");
    for (int i = 0; i < o.n_buffers; ++i)
      arv_stream_push_buffer(stream, arv_buffer_new_allocate(payload));
    arv_camera_start_acquisition(camera, &error);
    check(error, who, "AcquisitionStart");
  }

  // Counts the frames missing between the previous frame id and `id`. GigE
  // Vision 1.x block ids are 16 bits, skip 0 and wrap 65535 -> 1, so they are
  // compared modulo 65535; extended (64-bit) ids compare directly. Id 0 is
  // no id: Aravis gives it to a frame whose leader packet was lost. Such a
  // frame did arrive (incomplete), so it fills one place in the next gap.
  void note_frame_id(uint64_t id, CaptureCounters& counters) {
    if (id == 0) {
      ++without_id;
      return;
    }
    if (has_last_id) {
      uint64_t step = 0;
      if (id <= 0xFFFF && last_id <= 0xFFFF)
        step = (id + 65535 - last_id) % 65535;
      else if (id > last_id)
        step = id - last_id;
      if (step > 1) counters.lost += step - 1 - std::min(step - 1, without_id);
    }
    has_last_id = true;
    last_id = id;
    without_id = 0;
  }
};

GigeSource::GigeSource(std::string device, CaptureOptions options)
    : device_(std::move(device)), options_(std::move(options)) {}

GigeSource::~GigeSource() {
  close();
}

void GigeSource::open() {
  if (impl_) return;
  auto impl = std::make_unique<Impl>();
  const std::string who = name();
  impl->connect(device_, who);
  // Closes what was opened so far if a step below throws.
  struct Guard {
    GigeSource* self;
    std::unique_ptr<Impl>* impl;
    bool armed = true;
    ~Guard() {
      if (!armed) return;
      self->impl_ = std::move(*impl);
      self->close();
    }
  } guard{this, &impl};

  identity_ = identity_of(impl->camera);
  impl->control_lost_handler = g_signal_connect(arv_camera_get_device(impl->camera), "control-lost",
                                                G_CALLBACK(on_control_lost), &impl->control_lost);
  configure(impl->camera, options_, who);
  clock_ = CameraClock();
  latch_clock(impl->camera, &clock_);
  impl->start_stream(options_, who);

  guard.armed = false;
  impl_ = std::move(impl);
  counters_ = {};
}

void GigeSource::trigger() {
  if (!impl_) throw CaptureError(name(), "trigger() before open()");
  // Frames already queued were exposed before this trigger: not the one asked for.
  while (ArvBuffer* buffer = arv_stream_try_pop_buffer(impl_->stream)) {
    impl_->note_frame_id(arv_buffer_get_frame_id(buffer), counters_);
    if (arv_buffer_get_status(buffer) == ARV_BUFFER_STATUS_SUCCESS)
      ++counters_.discarded;
    else
      ++counters_.incomplete;
    arv_stream_push_buffer(impl_->stream, buffer);
  }
  if (!options_.software_trigger) return;
  GError* error = nullptr;
  arv_camera_software_trigger(impl_->camera, &error);
  if (error != nullptr) {
    impl_->unreachable = true;
    throw CaptureError(name(), "TriggerSoftware failed: " + take_message(error));
  }
  impl_->trigger_pending = true;
}

Frame GigeSource::grab(std::chrono::milliseconds timeout) {
  if (!impl_) throw CaptureError(name(), "grab() before open()");
  const std::string who = name();
  for (int attempt = 0;; ++attempt) {
    // Free run: wait again. Software trigger: trigger again, but only for a
    // trigger of ours still unanswered (never expose a frame nobody asked for).
    const bool may_retry =
        attempt < options_.retries && (!options_.software_trigger || impl_->trigger_pending);
    ArvBuffer* buffer =
        arv_stream_timeout_pop_buffer(impl_->stream, static_cast<guint64>(timeout.count()) * 1000);
    if (impl_->control_lost.load()) {
      impl_->unreachable = true;
      throw CaptureControlLost(who,
                               "control of the camera lost: it stopped hearing this "
                               "controller's heartbeat in time, or another application took it");
    }
    if (buffer == nullptr) {
      ++counters_.timeouts;
      if (!may_retry)
        throw CaptureTimeout(who, "no frame within " + std::to_string(timeout.count()) +
                                      " ms, after " + std::to_string(attempt) + " retries");
      ++counters_.retries;
      if (options_.software_trigger) trigger();
      continue;
    }
    impl_->note_frame_id(arv_buffer_get_frame_id(buffer), counters_);
    const uint64_t frame_id = arv_buffer_get_frame_id(buffer);
    const Payload payload = payload_of(buffer);
    if (payload.unreadable_format) {
      arv_stream_push_buffer(impl_->stream, buffer);
      throw CaptureError(who, "the camera sends pixel format " + pixel_format_name(payload.format) +
                                  ", which the capture path does not read; set "
                                  "capture.pixel_format to one of " +
                                  readable_pixel_formats());
    }
    if (payload.image.empty()) {
      ++counters_.incomplete;
      arv_stream_push_buffer(impl_->stream, buffer);
      if (!may_retry)
        throw CaptureError(who, "frame " + std::to_string(frame_id) + " incomplete (" +
                                    payload.problem + "), after " + std::to_string(attempt) +
                                    " retries");
      ++counters_.retries;
      if (options_.software_trigger) trigger();
      continue;
    }
    Frame frame = frame_of(buffer, payload, &clock_);
    frame.origin = who;
    arv_stream_push_buffer(impl_->stream, buffer);
    ++counters_.delivered;
    impl_->trigger_pending = false;
    return frame;
  }
}

bool GigeSource::realtime_receiver() const {
  return impl_ && impl_->realtime.load() == 2;
}

void GigeSource::close() {
  if (!impl_) return;
  if (impl_->camera != nullptr) {
    if (impl_->stream != nullptr && !impl_->unreachable)
      arv_camera_stop_acquisition(impl_->camera, nullptr);
    if (impl_->control_lost_handler != 0)
      g_signal_handler_disconnect(arv_camera_get_device(impl_->camera),
                                  impl_->control_lost_handler);
  }
  if (impl_->stream != nullptr) g_object_unref(impl_->stream);
  if (impl_->camera != nullptr) g_object_unref(impl_->camera);
  impl_.reset();
}

}  // namespace vision
