// What telemetry.cpp and control.cpp share: the process-wide ZeroMQ context
// and small socket helpers. Not part of rig_telemetry's public API.
#pragma once

#include <chrono>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <zmq.hpp>

#include "rig/telemetry/telemetry.hpp"

namespace rig::telemetry::detail {

// The one context of the process (see telemetry.hpp for why it is never destroyed).
zmq::context_t& context();

// A socket of `type` with linger 0 (destructors never wait for unsent
// messages) and IPv6 enabled when `endpoint` has a bracketed IPv6 host.
zmq::socket_t make_socket(zmq::socket_type type, const std::string& endpoint);

// zmq::poll that treats an interrupted wait (EINTR) as "nothing ready".
int poll(zmq::pollitem_t* items, size_t count, std::chrono::milliseconds timeout);

// Whole milliseconds until `deadline`, rounded up (so a wait never ends early);
// zero or less once it has passed.
inline std::chrono::milliseconds time_left(std::chrono::steady_clock::time_point deadline) {
  return std::chrono::ceil<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
}

// Receives every frame of the next message (dontwait); returns false if none
// is queued. Frames after the first are appended, so a multipart message is
// read whole and can be rejected as one.
bool receive_all(zmq::socket_t& socket, std::string& text, int& frames);

// The control server's answer to one request of `frames` frames whose bytes
// are `request` (docs/telemetry.md): acts on `state` and returns the reply
// ({"ok": true, "command", "status": status_fn()} or {"ok": false,
// "error"}). Any bytes at all give a reply; only status_fn may throw.
nlohmann::json answer_control_request(const std::string& request, int frames, ControlState& state,
                                      const std::function<nlohmann::json()>& status_fn);

}  // namespace rig::telemetry::detail
