// Pause/abort state, the REP control server and the REQ client.
#include <atomic>
#include <thread>

#include "config/json.hpp"
#include "rig/telemetry/telemetry.hpp"
#include "telemetry_internal.hpp"

namespace rig::telemetry {

// ---- ControlState ----

void ControlState::request_pause() {
  std::lock_guard<std::mutex> lock(mutex_);
  pause_requested_ = true;
  changed_.notify_all();
}

void ControlState::request_resume() {
  std::lock_guard<std::mutex> lock(mutex_);
  pause_requested_ = false;
  paused_by_controller_ = false;
  changed_.notify_all();
}

void ControlState::request_abort(const std::string& reason) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!abort_requested_) abort_reason_ = reason;
  abort_requested_ = true;
  changed_.notify_all();
}

bool ControlState::pause_requested() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pause_requested_ || paused_by_controller_;
}

bool ControlState::paused_by_controller() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return paused_by_controller_;
}

bool ControlState::paused() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return holding_;
}

bool ControlState::abort_requested() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return abort_requested_;
}

std::string ControlState::abort_reason() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return abort_reason_;
}

bool ControlState::wait_while_paused() {
  std::unique_lock<std::mutex> lock(mutex_);
  holding_ = true;
  changed_.wait(
      lock, [this] { return abort_requested_ || !(pause_requested_ || paused_by_controller_); });
  holding_ = false;
  return !abort_requested_;
}

void ControlState::set_paused_by_controller(bool paused) {
  std::lock_guard<std::mutex> lock(mutex_);
  paused_by_controller_ = paused;
  changed_.notify_all();
}

// ---- ControlServer ----

namespace {

using nlohmann::json;

json failure(const std::string& error) {
  return json{{"ok", false}, {"error", error}};
}

// A control request is one short JSON object ({"command": ..., "reason": ...});
// anything bigger or deeper is not one.
const config::JsonLimits kRequestLimits{8, 64u << 10};

std::string trimmed(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t\r\n") - first + 1);
}

}  // namespace

namespace detail {

json answer_control_request(const std::string& request, int frames, ControlState& state,
                            const std::function<json()>& status_fn) {
  if (frames != 1)
    return failure("request has " + std::to_string(frames) +
                   " frames: expected one frame of JSON or a bare command word");
  std::string command;
  std::string reason;
  const std::string text = trimmed(request);
  if (!text.empty() && text.front() == '{') {
    json r;
    try {
      r = config::parse_json(text, "request", kRequestLimits);
    } catch (const config::JsonInputError& e) {
      return failure(e.what());
    }
    if (!r.is_object() || !r.contains("command") || !r["command"].is_string())
      return failure("request " + config::excerpt_json(r) +
                     " has no \"command\" string: expected {\"command\": \"status\"}");
    command = r["command"].get<std::string>();
    if (r.contains("reason") && r["reason"].is_string()) reason = r["reason"].get<std::string>();
  } else {
    command = text;
  }
  if (command == "pause") {
    state.request_pause();
  } else if (command == "resume") {
    state.request_resume();
  } else if (command == "abort") {
    state.request_abort(reason.empty() ? "abort requested over the control socket" : reason);
  } else if (command != "status") {
    return failure("unknown command \"" + config::excerpt(command) +
                   "\"; expected status, pause, resume or abort");
  }
  json status;
  try {
    if (status_fn) status = status_fn();
  } catch (const std::exception& e) {
    return failure("command \"" + config::excerpt(command) +
                   "\" done, but the status failed: " + e.what());
  }
  return json{{"ok", true}, {"command", command}, {"status", status}};
}

}  // namespace detail

struct ControlServer::Impl {
  zmq::socket_t socket;       // REP; used only on `thread` once it runs
  zmq::socket_t stop_inbox;   // PAIR; used only on `thread`
  zmq::socket_t stop_outbox;  // PAIR; used only by the destructor
  std::string endpoint;
  ControlState* state = nullptr;
  std::function<json()> status_fn;
  std::thread thread;

  void run() {
    for (;;) {
      zmq::pollitem_t items[] = {{stop_inbox.handle(), 0, ZMQ_POLLIN, 0},
                                 {socket.handle(), 0, ZMQ_POLLIN, 0}};
      try {
        detail::poll(items, 2, std::chrono::milliseconds(-1));
        if (items[0].revents & ZMQ_POLLIN) return;
        std::string request;
        int frames = 0;
        if (!(items[1].revents & ZMQ_POLLIN) || !detail::receive_all(socket, request, frames))
          continue;
        json reply;
        try {
          reply = detail::answer_control_request(request, frames, *state, status_fn);
        } catch (const std::exception& e) {
          reply = failure(std::string("internal error: ") + e.what());
        }
        const std::string text =
            reply.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
        (void)socket.send(zmq::buffer(text), zmq::send_flags::dontwait);
      } catch (const zmq::error_t& e) {
        if (e.num() == ETERM) return;
        // Anything else (a reply that could not be sent) leaves REP ready for
        // the next request; keep serving.
      }
    }
  }
};

ControlServer::ControlServer(const std::string& endpoint, ControlState& state,
                             std::function<nlohmann::json()> status_fn)
    : impl_(new Impl) {
  static std::atomic<unsigned> servers{0};
  const std::string stop_name = "inproc://rig-control-stop-" + std::to_string(servers++);
  impl_->state = &state;
  impl_->status_fn = std::move(status_fn);
  refuse_ipc_over_file(endpoint, "control endpoint");
  try {
    impl_->socket = detail::make_socket(zmq::socket_type::rep, endpoint);
    // A peer that sends a bigger message is disconnected before it is read.
    impl_->socket.set(zmq::sockopt::maxmsgsize, static_cast<int64_t>(kRequestLimits.max_bytes));
    impl_->socket.bind(endpoint);
    impl_->endpoint = impl_->socket.get(zmq::sockopt::last_endpoint);
  } catch (const zmq::error_t& e) {
    throw TelemetryError("cannot bind the control socket to \"" + endpoint + "\": " + e.what());
  }
  impl_->stop_inbox = detail::make_socket(zmq::socket_type::pair, stop_name);
  impl_->stop_inbox.bind(stop_name);
  impl_->stop_outbox = detail::make_socket(zmq::socket_type::pair, stop_name);
  impl_->stop_outbox.connect(stop_name);
  impl_->thread = std::thread([impl = impl_.get()] { impl->run(); });
}

ControlServer::~ControlServer() {
  try {
    (void)impl_->stop_outbox.send(zmq::str_buffer("stop"), zmq::send_flags::dontwait);
  } catch (const zmq::error_t&) {
    // Cannot happen on a connected inproc PAIR; the join below would then hang,
    // so there is nothing better to do than proceed.
  }
  if (impl_->thread.joinable()) impl_->thread.join();
}

std::string ControlServer::endpoint() const {
  return impl_->endpoint;
}

// ---- send_control ----

nlohmann::json send_control(const std::string& endpoint, const std::string& command,
                            std::chrono::milliseconds timeout, const std::string& reason) {
  json request{{"command", command}};
  if (!reason.empty()) request["reason"] = reason;
  const std::string no_answer =
      "no sweep answering at " + endpoint + " within " + std::to_string(timeout.count()) + " ms";
  // A fresh REQ socket per request: after a timeout REQ is stuck waiting for
  // the reply, so it is discarded with the request (linger 0).
  zmq::socket_t socket;
  try {
    socket = detail::make_socket(zmq::socket_type::req, endpoint);
    socket.connect(endpoint);
    if (!socket.send(zmq::buffer(request.dump()), zmq::send_flags::dontwait))
      throw TelemetryError(no_answer);
  } catch (const zmq::error_t& e) {
    throw TelemetryError("cannot connect to the control socket at \"" + endpoint +
                         "\": " + e.what());
  }
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + timeout;
  std::string text;
  int frames = 0;
  while (!detail::receive_all(socket, text, frames)) {
    const auto left = detail::time_left(deadline);
    if (left.count() <= 0) throw TelemetryError(no_answer);
    zmq::pollitem_t item{socket.handle(), 0, ZMQ_POLLIN, 0};
    detail::poll(&item, 1, left);
  }
  json reply;
  try {
    reply = config::parse_json(text, "reply from \"" + endpoint + "\"");
  } catch (const config::JsonInputError& e) {
    throw TelemetryError(e.what());
  }
  if (!reply.is_object() || !reply.contains("ok"))
    throw TelemetryError(
        "reply from \"" + endpoint +
        "\" is not a control reply (a JSON object with \"ok\"): " + config::excerpt(text));
  return reply;
}

}  // namespace rig::telemetry
