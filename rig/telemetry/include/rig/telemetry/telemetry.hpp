// Telemetry and control of a sweep over ZeroMQ.
//
// A sweep publishes one JSON object per message on an XPUB socket (run start,
// one per position, faults, state changes, run stop; see docs/telemetry.md
// and the message shapes in progress_view.hpp) and answers `status`, `pause`, `resume`
// and `abort` on a REP socket. `rig monitor` and `rig ctl` are the clients.
//
// ZeroMQ context: every object here uses one process-wide zmq::context_t,
// created on first use and deliberately never destroyed. One context means one
// I/O thread for the whole process and lets inproc:// endpoints connect across
// objects (inproc only works within one context); never destroying it means
// process exit can never block in zmq_ctx_term on a socket some thread still
// holds. Every socket is created with linger 0, so destructors return at once
// and unsent messages are dropped.
//
// Threads: ZeroMQ sockets are not thread-safe. TelemetryPublisher guards its
// socket with a mutex (publish() may be called from any thread);
// ControlServer's socket lives on the server's own thread; TelemetrySubscriber
// and send_control are for one thread at a time.
#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>

namespace rig::telemetry {

// A socket could not be bound or connected, a peer did not answer in time or
// sent something that is not a telemetry/control message. The message names
// the endpoint and the cause.
class TelemetryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// An endpoint is malformed, or would bind beyond this machine without
// allow_remote: bad input (`rig` exits 2), not a failure while running.
class EndpointError : public TelemetryError {
 public:
  using TelemetryError::TelemetryError;
};

// Where a sweep binds its sockets. Endpoints are ZeroMQ addresses:
// tcp://HOST:PORT (PORT may be * for a port chosen at bind time, read it back
// with endpoint()), ipc://PATH or inproc://NAME.
struct TelemetryEndpoints {
  std::string publish = "tcp://127.0.0.1:5556";  // PUB (XPUB) socket, JSON telemetry
  std::string control = "tcp://127.0.0.1:5557";  // REP socket, status/pause/resume/abort
  // Binding to anything but loopback (127.x.x.x, [::1], localhost, ipc://,
  // inproc://) needs this: the control socket has no authentication, so anyone
  // who can reach it can pause or abort the bench.
  bool allow_remote = false;
};

// Checks one endpoint's syntax (tcp://HOST:PORT with PORT 1..65535 or *,
// ipc://PATH, inproc://NAME) and, unless allow_remote, that it stays on this
// machine, and that an ipc:// path is not an existing file (see below).
// `what` names the endpoint in the message ("publish endpoint").
// Throws EndpointError naming the endpoint, the value and what was expected.
void validate_endpoint(const std::string& endpoint, bool allow_remote, const std::string& what);

// libzmq deletes whatever is at an ipc:// path before it binds. Throws
// EndpointError when `endpoint` is ipc://PATH and PATH exists (as anything,
// a symbolic link included) but is not a socket; a socket left by an earlier
// run is replaced as before; also when PATH is longer than a Unix socket's
// path can be (107 bytes) or its folder does not exist. The publisher and
// the control server check this before they bind.
void refuse_ipc_over_file(const std::string& endpoint, const std::string& what);

// Checks both endpoints as validate_endpoint does, and that they differ.
// Throws EndpointError (a TelemetryError) naming the offending endpoint.
void validate_endpoints(const TelemetryEndpoints& endpoints);

// Whether a (syntactically valid) endpoint stays on this machine.
bool is_loopback_endpoint(const std::string& endpoint);

// Publishes telemetry: one JSON object per message, one frame of UTF-8 JSON
// text, every message with a string "type". The socket is an XPUB so the
// publisher sees subscriptions arrive: wait_for_subscribers() is the handshake
// that guarantees a subscriber gets every message published after it returns.
class TelemetryPublisher {
 public:
  // Binds to `endpoint` (not validated here: call validate_endpoints first).
  // Throws TelemetryError naming the endpoint if it cannot bind (port busy,
  // malformed address).
  explicit TelemetryPublisher(const std::string& endpoint);
  ~TelemetryPublisher();
  TelemetryPublisher(const TelemetryPublisher&) = delete;
  TelemetryPublisher& operator=(const TelemetryPublisher&) = delete;

  // Sends `message` to every subscriber. Thread-safe. Never blocks the sweep:
  // a subscriber whose queue is full (1000 messages) misses the message.
  // Strings that are not valid UTF-8 are sent with U+FFFD in place of bad bytes.
  // Precondition: `message` is an object with a string "type"
  // (std::invalid_argument otherwise).
  void publish(const nlohmann::json& message);

  // Blocks until at least `count` subscribers are subscribed or `timeout`
  // passes; returns whether they are. Counts subscribe minus unsubscribe
  // messages (a subscriber that disconnects is unsubscribed), so a subscriber
  // counts once per topic it subscribes to (TelemetrySubscriber: one).
  // Holds the socket's lock for at most 10 ms at a time, so publish() from
  // another thread is delayed by at most that while this waits.
  bool wait_for_subscribers(int count, std::chrono::milliseconds timeout);

  // Subscribers currently subscribed, as of the last publish() or wait.
  int subscribers() const;

  // The bound endpoint as ZeroMQ reports it (ZMQ_LAST_ENDPOINT), e.g.
  // tcp://127.0.0.1:41234 after binding tcp://127.0.0.1:*.
  std::string endpoint() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Pause and abort requests shared between the controller's thread and the
// control server's thread. All members are thread-safe.
class ControlState {
 public:
  // An operator asked to pause after the current position.
  void request_pause();
  // Clears a pause, whether an operator or the controller asked for it.
  void request_resume();
  // Asks the sweep to stop after the current position; also ends a pause.
  // The first reason given is kept.
  void request_abort(const std::string& reason);

  // A pause is in force (asked by an operator or by the controller).
  bool pause_requested() const;
  // The controller asked for this pause itself (e.g. a bench alarm with policy "pause").
  bool paused_by_controller() const;
  // The controller's thread is held in wait_while_paused() right now: the
  // sweep has actually stopped between positions (pause_requested() && !paused()
  // means it is still finishing a position).
  bool paused() const;
  bool abort_requested() const;
  std::string abort_reason() const;

  // The controller calls this between positions. Returns true at once if no
  // pause is in force; otherwise blocks until resume or abort. Returns false
  // if an abort was requested (before or during the wait).
  bool wait_while_paused();

  // The controller pauses (true) or un-pauses (false) the sweep itself; a
  // resume from an operator also clears it.
  void set_paused_by_controller(bool paused);

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  bool pause_requested_ = false;
  bool paused_by_controller_ = false;
  bool holding_ = false;
  bool abort_requested_ = false;
  std::string abort_reason_;
};

// Answers control requests on a REP socket, on its own thread.
// Requests: JSON {"command": "status"|"pause"|"resume"|"abort", "reason"?: "..."}
// or the bare command word as plain text. Replies (JSON):
//   {"ok": true, "command": "pause", "status": status_fn()}
//   {"ok": false, "error": "unknown command \"x\"; expected status, pause, resume or abort"}
// pause/resume/abort act on `state` before status_fn() is called for the reply.
// An abort without a reason is recorded as "abort requested over the control socket".
class ControlServer {
 public:
  // Binds `endpoint` (not validated here: call validate_endpoints first) and
  // starts the thread. Throws TelemetryError naming the endpoint if it cannot
  // bind. `state` must outlive the server. `status_fn` runs on the server's
  // thread, so it must be thread-safe; if it throws, the reply is ok:false
  // with its message.
  ControlServer(const std::string& endpoint, ControlState& state,
                std::function<nlohmann::json()> status_fn);
  // Stops the thread (at once, not after a poll period) and closes the socket.
  ~ControlServer();
  ControlServer(const ControlServer&) = delete;
  ControlServer& operator=(const ControlServer&) = delete;

  // The bound endpoint as ZeroMQ reports it (see TelemetryPublisher::endpoint).
  std::string endpoint() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Sends one control command to the sweep at `endpoint` and returns its reply
// (the JSON object above, ok true or false). `reason` is sent only when not
// empty. Throws TelemetryError "no sweep answering at <endpoint> within N ms"
// if no reply comes within `timeout` (the REQ socket is then discarded), or
// naming the endpoint if the reply is not a JSON object.
nlohmann::json send_control(const std::string& endpoint, const std::string& command,
                            std::chrono::milliseconds timeout, const std::string& reason = "");

// Receives telemetry: connects to a publisher and subscribes to everything.
// Connecting succeeds even if nothing listens yet; messages published before
// the subscription reaches the publisher are not seen (use
// TelemetryPublisher::wait_for_subscribers as the handshake).
class TelemetrySubscriber {
 public:
  // Throws TelemetryError naming the endpoint if it is malformed.
  explicit TelemetrySubscriber(const std::string& endpoint);
  ~TelemetrySubscriber();
  TelemetrySubscriber(const TelemetrySubscriber&) = delete;
  TelemetrySubscriber& operator=(const TelemetrySubscriber&) = delete;

  // The next message, or nullopt if none arrives within `timeout`. Throws
  // TelemetryError naming the endpoint if a message is not a JSON object
  // (the message is consumed; the next call receives the one after it).
  std::optional<nlohmann::json> receive(std::chrono::milliseconds timeout);

  std::string endpoint() const;  // as given to the constructor

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rig::telemetry
