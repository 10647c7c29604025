// vision::CameraClock: a camera's timestamps (ns on the camera's own tick
// counter) mapped to host time (ns since the Unix epoch, CLOCK_REALTIME), as
// host = camera + offset.
//
// Two ways to learn the offset, the better one kept:
//
//  * Latch (GigE Vision GevTimestampControlLatch, then GevTimestampValue):
//    the host reads its clock (h0), asks the camera to latch its counter,
//    reads the latched value c, reads its clock again (h1). The latch
//    happened between h0 and h1, so offset = (h0 + h1) / 2 - c with an error
//    of at most (h1 - h0) / 2 (half the round trip of two GVCP commands,
//    ~0.1-1 ms on Ethernet) plus one camera tick. Of several latches the one
//    with the narrowest bracket is kept.
//
//  * Arrival: each frame stamped c (start of exposure) was whole on the host
//    at a (host clock), and a frame cannot arrive before it was exposed, so
//    offset <= a - c for every frame. The smallest a - c seen is kept: the
//    mapped times are then late by the smallest exposure + readout +
//    transfer time seen (unknown to the host; at least the exposure time),
//    never early. Used when the camera has no latch.
//
// Neither models drift: a camera's crystal differs from the host's by up to
// ~50 ppm, 0.05 ms per second since the latch; latch again (or rely on the
// arrival bound, which follows the latest frames only if it shrinks).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace vision {

class CameraClock {
 public:
  enum class Method { kNone, kLatch, kArrival };

  // A latch bracketed by host times (ns since the epoch); h0 <= h1.
  void add_latch(int64_t host_before_ns, int64_t camera_ns, int64_t host_after_ns,
                 int64_t tick_ns = 1);
  // A frame's camera timestamp and its host arrival time. Ignored once a latch is known.
  void add_arrival(int64_t camera_ns, int64_t host_arrival_ns);

  Method method() const { return method_; }
  // host = camera + offset_ns(); 0 when method() is kNone.
  int64_t offset_ns() const { return offset_ns_; }
  // Latch: the bound on |error| (half the bracket plus one tick). Arrival: 0,
  // the mapped time being late by an amount the host cannot measure (above).
  int64_t error_bound_ns() const { return error_bound_ns_; }
  // The camera time on the host clock; nothing before any latch or arrival.
  std::optional<int64_t> to_host_ns(int64_t camera_ns) const;
  // "latch, +- 0.12 ms", "arrival (late by the transfer time)", "none".
  std::string describe() const;

 private:
  Method method_ = Method::kNone;
  int64_t offset_ns_ = 0;
  int64_t error_bound_ns_ = 0;
};

}  // namespace vision
