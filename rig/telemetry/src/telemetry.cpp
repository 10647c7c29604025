// Telemetry endpoints, the XPUB publisher and the SUB subscriber.
#include "rig/telemetry/telemetry.hpp"

#include <sys/stat.h>
#include <sys/un.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <mutex>

#include "config/json.hpp"
#include "telemetry_internal.hpp"

namespace rig::telemetry {

namespace detail {

zmq::context_t& context() {
  // Never destroyed: see telemetry.hpp (exit must not wait in zmq_ctx_term).
  static zmq::context_t* const process_context = new zmq::context_t(1);
  return *process_context;
}

zmq::socket_t make_socket(zmq::socket_type type, const std::string& endpoint) {
  zmq::socket_t socket(context(), type);
  socket.set(zmq::sockopt::linger, 0);
  if (endpoint.rfind("tcp://[", 0) == 0) socket.set(zmq::sockopt::ipv6, true);
  return socket;
}

int poll(zmq::pollitem_t* items, size_t count, std::chrono::milliseconds timeout) {
  try {
    return zmq::poll(items, count, timeout);
  } catch (const zmq::error_t& e) {
    if (e.num() == EINTR) return 0;
    throw;
  }
}

bool receive_all(zmq::socket_t& socket, std::string& text, int& frames) {
  zmq::message_t frame;
  if (!socket.recv(frame, zmq::recv_flags::dontwait)) return false;
  text = frame.to_string();
  frames = 1;
  while (frame.more()) {
    if (!socket.recv(frame, zmq::recv_flags::none)) break;
    text += frame.to_string();
    ++frames;
  }
  return true;
}

}  // namespace detail

namespace {

using detail::make_socket;

const char* const kExpectedEndpoint =
    "expected tcp://HOST:PORT (PORT 1..65535 or *), ipc://PATH or inproc://NAME";

struct ParsedEndpoint {
  std::string transport;  // tcp, ipc, inproc
  std::string host;       // tcp only, without IPv6 brackets
};

bool is_number(const std::string& s) {
  return !s.empty() && s.size() <= 5 &&
         std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

ParsedEndpoint parse_endpoint(const std::string& endpoint, const std::string& what) {
  auto malformed = [&](const std::string& why) {
    return EndpointError(what + " \"" + endpoint + "\" is malformed (" + why +
                         "): " + kExpectedEndpoint);
  };
  const auto scheme_end = endpoint.find("://");
  if (scheme_end == std::string::npos) throw malformed("no transport://");
  ParsedEndpoint p;
  p.transport = endpoint.substr(0, scheme_end);
  const std::string rest = endpoint.substr(scheme_end + 3);
  if (p.transport == "ipc" || p.transport == "inproc") {
    if (rest.empty()) throw malformed("empty " + p.transport + " name");
    return p;
  }
  if (p.transport != "tcp") throw malformed("transport \"" + p.transport + "\" is not supported");
  std::string port;
  if (!rest.empty() && rest.front() == '[') {
    const auto close = rest.find(']');
    if (close == std::string::npos || close + 1 >= rest.size() || rest[close + 1] != ':')
      throw malformed("IPv6 host needs the form [ADDRESS]:PORT");
    p.host = rest.substr(1, close - 1);
    port = rest.substr(close + 2);
  } else {
    const auto colon = rest.rfind(':');
    if (colon == std::string::npos) throw malformed("no :PORT");
    p.host = rest.substr(0, colon);
    port = rest.substr(colon + 1);
    if (p.host.find(':') != std::string::npos)
      throw malformed("IPv6 hosts go in brackets, e.g. tcp://[::1]:5556");
  }
  if (p.host.empty()) throw malformed("empty host");
  if (port != "*" && !(is_number(port) && std::stoi(port) >= 1 && std::stoi(port) <= 65535))
    throw malformed("port \"" + port + "\" is not 1..65535 or *");
  return p;
}

// 127.0.0.0/8 written as a dotted quad.
bool is_ipv4_loopback(const std::string& host) {
  int octets = 0;
  size_t start = 0;
  std::string first;
  while (start <= host.size()) {
    const auto dot = std::min(host.find('.', start), host.size());
    const std::string octet = host.substr(start, dot - start);
    if (!is_number(octet) || octet.size() > 3 || std::stoi(octet) > 255) return false;
    if (octets == 0) first = octet;
    ++octets;
    start = dot + 1;
  }
  return octets == 4 && std::stoi(first) == 127;
}

bool is_loopback(const ParsedEndpoint& p) {
  if (p.transport != "tcp") return true;  // ipc and inproc never leave the machine
  return p.host == "localhost" || p.host == "::1" || is_ipv4_loopback(p.host);
}

}  // namespace

void refuse_ipc_over_file(const std::string& endpoint, const std::string& what) {
  const std::string prefix = "ipc://";
  if (endpoint.rfind(prefix, 0) != 0) return;
  const std::string path = endpoint.substr(prefix.size());
  // A Unix socket's path fits sockaddr_un::sun_path with its NUL; libzmq
  // would refuse a longer one only when binding, after the checks.
  constexpr std::size_t kMaxPath = sizeof(sockaddr_un{}.sun_path) - 1;
  if (path.size() > kMaxPath)
    throw EndpointError(what + " \"" + config::excerpt(endpoint) + "\": the path is " +
                        std::to_string(path.size()) + " bytes long: expected at most " +
                        std::to_string(kMaxPath) + " (a Unix socket's path)");
  // The socket is created in PATH's folder, which must exist: binding fails
  // otherwise, after the sweep file was taken.
  const std::size_t slash = path.rfind('/');
  const std::string folder = slash == std::string::npos ? "." : path.substr(0, slash + 1);
  struct stat st {};
  if (::stat(folder.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw EndpointError(what + " \"" + config::excerpt(endpoint) + "\": \"" +
                        config::excerpt(folder) +
                        "\" is not an existing folder: expected a path in one");
  // lstat: a symbolic link is not followed (libzmq would unlink the link).
  if (::lstat(path.c_str(), &st) != 0 || S_ISSOCK(st.st_mode)) return;
  throw EndpointError(what + " \"" + endpoint + "\": \"" + path +
                      "\" exists and is not a socket (binding would delete it): expected a path "
                      "that does not exist or a socket left by an earlier run");
}

void validate_endpoint(const std::string& endpoint, bool allow_remote, const std::string& what) {
  const ParsedEndpoint p = parse_endpoint(endpoint, what);
  refuse_ipc_over_file(endpoint, what);
  if (!allow_remote && !is_loopback(p))
    throw EndpointError(what + " \"" + endpoint + "\" binds beyond this machine (host \"" + p.host +
                        "\"): expected a loopback host (127.0.0.1, [::1], localhost), ipc:// or "
                        "inproc://, or allow remote binding explicitly (anyone who can reach the "
                        "control socket can pause or abort the sweep)");
}

void validate_endpoints(const TelemetryEndpoints& endpoints) {
  validate_endpoint(endpoints.publish, endpoints.allow_remote, "publish endpoint");
  validate_endpoint(endpoints.control, endpoints.allow_remote, "control endpoint");
  if (endpoints.publish == endpoints.control)
    throw EndpointError("publish and control endpoints are both \"" + endpoints.publish +
                        "\": expected two different endpoints");
}

bool is_loopback_endpoint(const std::string& endpoint) {
  return is_loopback(parse_endpoint(endpoint, "endpoint"));
}

// ---- TelemetryPublisher ----

struct TelemetryPublisher::Impl {
  mutable std::mutex mutex;
  zmq::socket_t socket;
  std::string endpoint;
  int subscribers = 0;

  // Reads the subscription messages XPUB has queued (first byte 1: subscribe,
  // 0: unsubscribe). Caller holds `mutex`.
  void read_subscriptions() {
    std::string text;
    int frames = 0;
    while (detail::receive_all(socket, text, frames)) {
      if (text.empty()) continue;
      if (text[0] == 1) ++subscribers;
      if (text[0] == 0) subscribers = std::max(0, subscribers - 1);
    }
  }
};

TelemetryPublisher::TelemetryPublisher(const std::string& endpoint) : impl_(new Impl) {
  refuse_ipc_over_file(endpoint, "publish endpoint");
  try {
    impl_->socket = make_socket(zmq::socket_type::xpub, endpoint);
    // A slow subscriber loses messages beyond this rather than holding memory
    // without bound; the sweep itself never waits (PUB semantics).
    impl_->socket.set(zmq::sockopt::sndhwm, 1000);
    // Report every subscribe and unsubscribe, not only the first per topic,
    // so subscribers can be counted.
    impl_->socket.set(zmq::sockopt::xpub_verboser, true);
    impl_->socket.bind(endpoint);
    impl_->endpoint = impl_->socket.get(zmq::sockopt::last_endpoint);
  } catch (const zmq::error_t& e) {
    throw TelemetryError("cannot bind the telemetry publisher to \"" + endpoint +
                         "\": " + e.what());
  }
}

TelemetryPublisher::~TelemetryPublisher() = default;

void TelemetryPublisher::publish(const nlohmann::json& message) {
  if (!message.is_object() || !message.contains("type") || !message["type"].is_string())
    throw std::invalid_argument("telemetry message needs a string \"type\", got: " +
                                message.dump().substr(0, 200));
  const std::string text = message.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  std::lock_guard<std::mutex> lock(impl_->mutex);
  try {
    impl_->read_subscriptions();
    // XPUB drops the message for a subscriber at its high-water mark; dontwait
    // makes sure nothing here can ever block.
    (void)impl_->socket.send(zmq::buffer(text), zmq::send_flags::dontwait);
  } catch (const zmq::error_t& e) {
    throw TelemetryError("cannot publish telemetry on \"" + impl_->endpoint + "\": " + e.what());
  }
}

bool TelemetryPublisher::wait_for_subscribers(int count, std::chrono::milliseconds timeout) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + timeout;
  // Short slices so publish() from another thread waits at most one slice for the lock.
  constexpr std::chrono::milliseconds kSlice(10);
  for (;;) {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->read_subscriptions();
    if (impl_->subscribers >= count) return true;
    const auto left = detail::time_left(deadline);
    if (left.count() <= 0) return false;
    zmq::pollitem_t item{impl_->socket.handle(), 0, ZMQ_POLLIN, 0};
    detail::poll(&item, 1, std::min(left, kSlice));
  }
}

int TelemetryPublisher::subscribers() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->subscribers;
}

std::string TelemetryPublisher::endpoint() const {
  return impl_->endpoint;
}

// ---- TelemetrySubscriber ----

struct TelemetrySubscriber::Impl {
  zmq::socket_t socket;
  std::string endpoint;
};

TelemetrySubscriber::TelemetrySubscriber(const std::string& endpoint) : impl_(new Impl) {
  impl_->endpoint = endpoint;
  try {
    impl_->socket = make_socket(zmq::socket_type::sub, endpoint);
    impl_->socket.set(zmq::sockopt::subscribe, "");
    impl_->socket.connect(endpoint);
  } catch (const zmq::error_t& e) {
    throw TelemetryError("cannot subscribe to telemetry at \"" + endpoint + "\": " + e.what());
  }
}

TelemetrySubscriber::~TelemetrySubscriber() = default;

std::optional<nlohmann::json> TelemetrySubscriber::receive(std::chrono::milliseconds timeout) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + timeout;
  std::string text;
  int frames = 0;
  for (;;) {
    if (detail::receive_all(impl_->socket, text, frames)) break;
    const auto left = detail::time_left(deadline);
    if (left.count() <= 0) return std::nullopt;
    zmq::pollitem_t item{impl_->socket.handle(), 0, ZMQ_POLLIN, 0};
    detail::poll(&item, 1, left);
  }
  nlohmann::json message;
  try {
    message = config::parse_json(text, "telemetry from \"" + impl_->endpoint + "\"");
  } catch (const config::JsonInputError& e) {
    throw TelemetryError(e.what());
  }
  if (!message.is_object() || frames != 1)
    throw TelemetryError("telemetry from \"" + impl_->endpoint +
                         "\" is not a single-frame JSON object: " + config::excerpt(text));
  return message;
}

std::string TelemetrySubscriber::endpoint() const {
  return impl_->endpoint;
}

}  // namespace rig::telemetry
