// Aravis 0.8's simulated GigE Vision camera (ArvGvFakeCamera) runs one thread
// that, once it has streamed a frame, waits for its next frame time (in
// software trigger mode: the next look for a trigger, every 1 /
// trigger_poll_hz) with g_poll on its control sockets. It computes that
// timeout in whole milliseconds, rounded down, and polls with a zero timeout
// for the last (sub-)millisecond. With a 1 ms trigger period
// (trigger_poll_hz = 1000, the simulator's default, for a 1 ms trigger
// latency) the timeout is always zero: the thread spins on g_poll and keeps
// a core busy for as long as acquisition is on, frames triggered or not. On
// a two-core machine running rig sweep beside rig sim, half of the machine.
//
// This file defines g_poll. A program that links sim_camera takes it in
// place of GLib's: the executable comes first in the dynamic linker's search
// order, and libaravis calls g_poll through its PLT. It is GLib's g_poll
// (reached with dlsym(RTLD_NEXT)) for every call but one kind: a zero
// timeout on a camera thread marked by pace_camera_thread. That call, the
// spin, waits on the same descriptors until the camera's next frame time as
// Aravis computes it (arv_fake_camera_get_sleep_time_for_next_frame, the
// moment the loop is spinning towards). A control packet still wakes it at
// once and the trigger is still looked for at the same moments, so the
// camera answers as before; it sleeps in between.
#include "trigger_pacing.hpp"

#include <dlfcn.h>
#include <poll.h>

#include <algorithm>
#include <cstddef>
#include <ctime>

namespace sim::camera::detail {

namespace {

// The camera whose thread this is; null on every other thread.
thread_local ArvFakeCamera* paced_camera = nullptr;

// The longest wait in place of a spin (µs): Aravis's own longest poll, after
// which its loop looks at its cancel flag.
constexpr guint64 kMaxWaitUs = 100000;

gint glib_poll(GPollFD* fds, guint nfds, gint timeout) {
  using GPollFn = gint (*)(GPollFD*, guint, gint);
  static const auto glib = reinterpret_cast<GPollFn>(dlsym(RTLD_NEXT, "g_poll"));
  // GLib's g_poll on Linux is poll(2) on the same array.
  return glib != nullptr ? glib(fds, nfds, timeout)
                         : poll(reinterpret_cast<pollfd*>(fds), nfds, timeout);
}

}  // namespace

void pace_camera_thread(ArvFakeCamera* camera) {
  paced_camera = camera;
}

}  // namespace sim::camera::detail

static_assert(sizeof(GPollFD) == sizeof(pollfd) && offsetof(GPollFD, fd) == offsetof(pollfd, fd) &&
                  offsetof(GPollFD, events) == offsetof(pollfd, events) &&
                  offsetof(GPollFD, revents) == offsetof(pollfd, revents),
              "GPollFD is not struct pollfd");

extern "C" gint g_poll(GPollFD* fds, guint nfds, gint timeout) {
  ArvFakeCamera* camera = sim::camera::detail::paced_camera;
  if (timeout != 0 || camera == nullptr) return sim::camera::detail::glib_poll(fds, nfds, timeout);
  const guint64 wait_us = std::min(arv_fake_camera_get_sleep_time_for_next_frame(camera, nullptr),
                                   sim::camera::detail::kMaxWaitUs);
  const timespec wait{static_cast<time_t>(wait_us / 1000000),
                      static_cast<long>(wait_us % 1000000) * 1000};
  return ppoll(reinterpret_cast<pollfd*>(fds), nfds, &wait, nullptr);
}
