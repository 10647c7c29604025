#include "vision/v4l2_source.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <utility>

#include "vision/pixel_format.hpp"

namespace vision {
namespace {

// ioctl, restarted when a signal interrupts it.
int xioctl(int fd, unsigned long request, void* arg) {
  int result;
  do
    result = ioctl(fd, request, arg);
  while (result == -1 && errno == EINTR);
  return result;
}

std::string errno_text() {
  return std::strerror(errno);
}

uint64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<uint64_t>(ts.tv_nsec);
}

}  // namespace

V4l2Source::V4l2Source(std::string path, CaptureOptions options)
    : path_(std::move(path)), options_(std::move(options)) {}

V4l2Source::~V4l2Source() {
  close();
}

void V4l2Source::open() {
  if (fd_ >= 0) return;
  const std::string who = name();
  const int fd = ::open(path_.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw CaptureError(who, "cannot open the device: " + errno_text());
  fd_ = fd;
  auto fail = [&](const std::string& message) {
    close();
    throw CaptureError(who, message);
  };
  struct stat st {};
  if (fstat(fd_, &st) != 0 || !S_ISCHR(st.st_mode))
    fail("not a V4L2 device (not a character device)");
  v4l2_capability cap{};
  if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) != 0)
    fail("not a V4L2 device (VIDIOC_QUERYCAP: " + errno_text() + ")");
  auto field = [](const __u8* text, size_t size) {
    const char* begin = reinterpret_cast<const char*>(text);
    return std::string(begin, strnlen(begin, size));
  };
  identity_.vendor = field(cap.driver, sizeof cap.driver);
  identity_.model = field(cap.card, sizeof cap.card);
  identity_.serial = field(cap.bus_info, sizeof cap.bus_info);
  identity_.device_version = "driver " + std::to_string((cap.version >> 16) & 0xff) + "." +
                             std::to_string((cap.version >> 8) & 0xff) + "." +
                             std::to_string(cap.version & 0xff);
  const uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) fail("V4L2 device is not a video capture device");
  if (!(caps & V4L2_CAP_STREAMING)) fail("V4L2 capture device does not support streaming I/O");

  v4l2_format format{};
  format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(fd_, VIDIOC_G_FMT, &format) != 0) fail("VIDIOC_G_FMT: " + errno_text());
  if (options_.width) format.fmt.pix.width = static_cast<uint32_t>(*options_.width);
  if (options_.height) format.fmt.pix.height = static_cast<uint32_t>(*options_.height);
  format.fmt.pix.pixelformat = V4L2_PIX_FMT_GREY;
  format.fmt.pix.field = V4L2_FIELD_NONE;
  if (xioctl(fd_, VIDIOC_S_FMT, &format) != 0) fail("VIDIOC_S_FMT: " + errno_text());
  fourcc_ = format.fmt.pix.pixelformat;
  if (fourcc_ != V4L2_PIX_FMT_GREY && fourcc_ != V4L2_PIX_FMT_Y16 && fourcc_ != V4L2_PIX_FMT_YUYV &&
      fourcc_ != V4L2_PIX_FMT_MJPEG)
    fail("device offers " + fourcc_name(fourcc_) + ", not GREY, Y16, YUYV or MJPG");
  width_ = static_cast<int>(format.fmt.pix.width);
  height_ = static_cast<int>(format.fmt.pix.height);
  bytes_per_line_ = static_cast<int>(format.fmt.pix.bytesperline);

  v4l2_requestbuffers request{};
  request.count = static_cast<uint32_t>(options_.n_buffers);
  request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  request.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_REQBUFS, &request) != 0 || request.count == 0)
    fail("VIDIOC_REQBUFS (memory-mapped buffers): " + errno_text());
  for (uint32_t i = 0; i < request.count; ++i) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = i;
    if (xioctl(fd_, VIDIOC_QUERYBUF, &buffer) != 0) fail("VIDIOC_QUERYBUF: " + errno_text());
    void* start =
        mmap(nullptr, buffer.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, buffer.m.offset);
    if (start == MAP_FAILED) fail("mmap of buffer " + std::to_string(i) + ": " + errno_text());
    buffers_.push_back({start, buffer.length});
    if (xioctl(fd_, VIDIOC_QBUF, &buffer) != 0) fail("VIDIOC_QBUF: " + errno_text());
  }
  v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(fd_, VIDIOC_STREAMON, &type) != 0) fail("VIDIOC_STREAMON: " + errno_text());
  streaming_ = true;
  counters_ = {};
}

void V4l2Source::trigger() {
  if (fd_ < 0) throw CaptureError(name(), "trigger() before open()");
  not_before_ns_ = monotonic_ns();
}

Frame V4l2Source::grab(std::chrono::milliseconds timeout) {
  if (fd_ < 0) throw CaptureError(name(), "grab() before open()");
  const std::string who = name();
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  int attempt = 0;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd pfd{fd_, POLLIN, 0};
    const int ready = poll(&pfd, 1, static_cast<int>(std::max<int64_t>(0, left.count())));
    if (ready < 0 && errno != EINTR) throw CaptureError(who, "poll: " + errno_text());
    if (ready <= 0) {
      ++counters_.timeouts;
      throw CaptureTimeout(who, "no frame within " + std::to_string(timeout.count()) + " ms");
    }
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd_, VIDIOC_DQBUF, &buffer) != 0) {
      if (errno == EAGAIN) continue;
      throw CaptureError(who, "VIDIOC_DQBUF: " + errno_text() + " (device unplugged?)");
    }
    const uint64_t stamp_ns = static_cast<uint64_t>(buffer.timestamp.tv_sec) * 1000000000ull +
                              static_cast<uint64_t>(buffer.timestamp.tv_usec) * 1000ull;
    // Only a CLOCK_MONOTONIC timestamp compares with trigger()'s clock; a
    // device with another clock cannot tell stale frames and takes the next.
    const bool monotonic =
        (buffer.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
    const bool stale = monotonic && stamp_ns < not_before_ns_;
    bool corrupt = (buffer.flags & V4L2_BUF_FLAG_ERROR) != 0;
    Frame frame;
    if (!corrupt && !stale) {
      try {
        frame.image = v4l2_buffer_to_image(buffers_[buffer.index].start, buffer.bytesused, width_,
                                           height_, static_cast<size_t>(bytes_per_line_), fourcc_);
      } catch (const PixelFormatError&) {
        corrupt = true;  // short, or a JPEG that does not decode: a damaged frame
      }
    }
    if (xioctl(fd_, VIDIOC_QBUF, &buffer) != 0)
      throw CaptureError(who, "VIDIOC_QBUF: " + errno_text());
    if (stale) {
      ++counters_.discarded;
      continue;
    }
    if (corrupt) {
      ++counters_.incomplete;
      if (attempt++ >= options_.retries)
        throw CaptureError(who, "frame " + std::to_string(buffer.sequence) +
                                    " corrupt or short, after " + std::to_string(options_.retries) +
                                    " retries");
      ++counters_.retries;
      continue;
    }
    frame.frame_id = buffer.sequence;
    frame.significant_bits = fourcc_ == V4L2_PIX_FMT_Y16 ? 16 : 8;
    frame.camera_timestamp_ns = stamp_ns;
    frame.host_time = std::chrono::system_clock::now();
    frame.origin = who;
    ++counters_.delivered;
    return frame;
  }
}

void V4l2Source::close() {
  if (fd_ < 0) return;
  if (streaming_) {
    v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    xioctl(fd_, VIDIOC_STREAMOFF, &type);
    streaming_ = false;
  }
  for (const Mapping& m : buffers_)
    munmap(m.start, m.length);
  buffers_.clear();
  ::close(fd_);
  fd_ = -1;
}

}  // namespace vision
