// Camera timestamps on the host clock (see vision/camera_clock.hpp).
#include "vision/camera_clock.hpp"

#include <cstdio>

namespace vision {

void CameraClock::add_latch(int64_t host_before_ns, int64_t camera_ns, int64_t host_after_ns,
                            int64_t tick_ns) {
  if (host_after_ns < host_before_ns) return;  // a clock step between the reads: no bracket
  const int64_t half = (host_after_ns - host_before_ns) / 2;
  const int64_t bound = half + (host_after_ns - host_before_ns) % 2 + tick_ns;
  if (method_ == Method::kLatch && bound >= error_bound_ns_) return;
  method_ = Method::kLatch;
  offset_ns_ = host_before_ns + half - camera_ns;
  error_bound_ns_ = bound;
}

void CameraClock::add_arrival(int64_t camera_ns, int64_t host_arrival_ns) {
  if (method_ == Method::kLatch) return;
  const int64_t offset = host_arrival_ns - camera_ns;
  if (method_ == Method::kArrival && offset >= offset_ns_) return;
  method_ = Method::kArrival;
  offset_ns_ = offset;
  error_bound_ns_ = 0;
}

std::optional<int64_t> CameraClock::to_host_ns(int64_t camera_ns) const {
  if (method_ == Method::kNone) return std::nullopt;
  return camera_ns + offset_ns_;
}

std::string CameraClock::describe() const {
  switch (method_) {
    case Method::kLatch: {
      char text[64];
      std::snprintf(text, sizeof text, "latch, +- %.3f ms",
                    static_cast<double>(error_bound_ns_) * 1e-6);
      return text;
    }
    case Method::kArrival:
      return "arrival (late by the exposure, readout and transfer time)";
    default:
      return "none";
  }
}

}  // namespace vision
