// Telemetry publisher/subscriber, endpoint validation, and the control socket
// driven directly (no controller): a fake sweep loop stands in for it.
#include "rig/telemetry/telemetry.hpp"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <thread>
#include <zmq.hpp>

namespace {

using namespace std::chrono_literals;
using nlohmann::json;

// Generous: only reached when something is broken; a healthy loopback round
// trip takes well under a millisecond.
constexpr auto kPatience = 5000ms;

json position(int index, int plan_size) {
  return json{{"type", "position"},
              {"run_id", 1},
              {"plan_index", index},
              {"completed", index + 1},
              {"plan_size", plan_size},
              {"status", "ok"},
              {"elapsed_s", 0.5 * (index + 1)}};
}

// Spins (no sleep) until `condition` holds or kPatience passes.
template <class Condition>
bool eventually(Condition condition) {
  const auto deadline = std::chrono::steady_clock::now() + kPatience;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::yield();
  }
  return true;
}

TEST(TelemetryPublisher, ReportsThePortChosenAtBindTime) {
  rig::telemetry::TelemetryPublisher publisher("tcp://127.0.0.1:*");
  const std::string endpoint = publisher.endpoint();
  ASSERT_EQ(endpoint.rfind("tcp://127.0.0.1:", 0), 0u) << endpoint;
  const int port = std::stoi(endpoint.substr(std::string("tcp://127.0.0.1:").size()));
  EXPECT_GT(port, 0);
  EXPECT_LE(port, 65535);
}

TEST(TelemetryPublisher, SubscriberAfterHandshakeSeesRunStartEveryPositionAndRunStopInOrder) {
  rig::telemetry::TelemetryPublisher publisher("tcp://127.0.0.1:*");
  rig::telemetry::TelemetrySubscriber subscriber(publisher.endpoint());
  ASSERT_TRUE(publisher.wait_for_subscribers(1, kPatience));
  constexpr int kPositions = 50;
  publisher.publish({{"type", "run_start"}, {"run_id", 1}, {"plan_size", kPositions}});
  for (int i = 0; i < kPositions; ++i)
    publisher.publish(position(i, kPositions));
  publisher.publish({{"type", "run_stop"}, {"run_id", 1}, {"status", "completed"}});

  auto first = subscriber.receive(kPatience);
  ASSERT_TRUE(first);
  EXPECT_EQ((*first)["type"], "run_start");
  for (int i = 0; i < kPositions; ++i) {
    auto m = subscriber.receive(kPatience);
    ASSERT_TRUE(m) << "position " << i << " missing";
    EXPECT_EQ((*m)["type"], "position");
    EXPECT_EQ((*m)["plan_index"], i);
  }
  auto last = subscriber.receive(kPatience);
  ASSERT_TRUE(last);
  EXPECT_EQ((*last)["type"], "run_stop");
  EXPECT_FALSE(subscriber.receive(10ms)) << "nothing beyond what was published";
}

TEST(TelemetryPublisher, TwoSubscribersAreCountedAndBothReceive) {
  rig::telemetry::TelemetryPublisher publisher("tcp://127.0.0.1:*");
  rig::telemetry::TelemetrySubscriber a(publisher.endpoint());
  rig::telemetry::TelemetrySubscriber b(publisher.endpoint());
  ASSERT_TRUE(publisher.wait_for_subscribers(2, kPatience));
  EXPECT_EQ(publisher.subscribers(), 2);
  publisher.publish({{"type", "state"}, {"state", "paused"}});
  for (auto* s : {&a, &b}) {
    auto m = s->receive(kPatience);
    ASSERT_TRUE(m);
    EXPECT_EQ((*m)["state"], "paused");
  }
}

TEST(TelemetryPublisher, WaitForSubscribersReturnsFalseWhenNobodySubscribes) {
  rig::telemetry::TelemetryPublisher publisher("tcp://127.0.0.1:*");
  EXPECT_FALSE(publisher.wait_for_subscribers(1, 30ms));
  EXPECT_EQ(publisher.subscribers(), 0);
}

TEST(TelemetryPublisher, ADisconnectedSubscriberNoLongerCounts) {
  rig::telemetry::TelemetryPublisher publisher("tcp://127.0.0.1:*");
  {
    rig::telemetry::TelemetrySubscriber gone(publisher.endpoint());
    ASSERT_TRUE(publisher.wait_for_subscribers(1, kPatience));
  }
  rig::telemetry::TelemetrySubscriber staying(publisher.endpoint());
  ASSERT_TRUE(publisher.wait_for_subscribers(1, kPatience));
  // The unsubscription of the first and the subscription of the second both
  // arrive; until both are read the count may be 1 or 2, then it is 1.
  EXPECT_TRUE(eventually([&] {
    publisher.wait_for_subscribers(3, 1ms);
    return publisher.subscribers() == 1;
  }));
}

TEST(TelemetryPublisher, PublishWithoutSubscribersDoesNotBlock) {
  rig::telemetry::TelemetryPublisher publisher("tcp://127.0.0.1:*");
  // Far more than the high-water mark (1000): XPUB drops, never waits.
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 5000; ++i)
    publisher.publish(position(i, 5000));
  // A blocking publish would wait for ever; dropping takes microseconds per
  // message. 5 s is far above either a loaded machine's dropping time or
  // anything a sweep could tolerate.
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
}

TEST(TelemetryPublisher, ASlowSubscriberDoesNotBlockPublishing) {
  rig::telemetry::TelemetryPublisher publisher("tcp://127.0.0.1:*");
  rig::telemetry::TelemetrySubscriber never_reads(publisher.endpoint());
  ASSERT_TRUE(publisher.wait_for_subscribers(1, kPatience));
  for (int i = 0; i < 20000; ++i)
    publisher.publish(position(i, 20000));
  auto m = never_reads.receive(kPatience);
  ASSERT_TRUE(m);
  EXPECT_EQ((*m)["plan_index"], 0) << "the oldest messages are kept, later ones dropped";
}

TEST(TelemetryPublisher, RefusesAMessageWithoutType) {
  rig::telemetry::TelemetryPublisher publisher("tcp://127.0.0.1:*");
  EXPECT_THROW(publisher.publish({{"run_id", 1}}), std::invalid_argument);
  EXPECT_THROW(publisher.publish(json::array({1, 2})), std::invalid_argument);
  EXPECT_THROW(publisher.publish({{"type", 3}}), std::invalid_argument);
}

TEST(TelemetryPublisher, SendsInvalidUtf8WithReplacementCharacters) {
  rig::telemetry::TelemetryPublisher publisher("tcp://127.0.0.1:*");
  rig::telemetry::TelemetrySubscriber subscriber(publisher.endpoint());
  ASSERT_TRUE(publisher.wait_for_subscribers(1, kPatience));
  publisher.publish({{"type", "fault"}, {"message", std::string("bad \xff byte")}});
  auto m = subscriber.receive(kPatience);
  ASSERT_TRUE(m);
  EXPECT_EQ((*m)["message"], "bad \xEF\xBF\xBD byte");
}

TEST(TelemetryPublisher, BusyPortThrowsNamingTheEndpoint) {
  rig::telemetry::TelemetryPublisher first("tcp://127.0.0.1:*");
  try {
    rig::telemetry::TelemetryPublisher second(first.endpoint());
    FAIL() << "bound twice to " << first.endpoint();
  } catch (const rig::telemetry::TelemetryError& e) {
    EXPECT_NE(std::string(e.what()).find(first.endpoint()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("in use"), std::string::npos) << e.what();
  }
}

TEST(TelemetrySubscriber, ReceiveTimesOutWithNothingPublished) {
  rig::telemetry::TelemetryPublisher publisher("tcp://127.0.0.1:*");
  rig::telemetry::TelemetrySubscriber subscriber(publisher.endpoint());
  EXPECT_FALSE(subscriber.receive(20ms));
}

TEST(TelemetrySubscriber, WorksOverInproc) {
  rig::telemetry::TelemetryPublisher publisher("inproc://telemetry-test-inproc");
  rig::telemetry::TelemetrySubscriber subscriber(publisher.endpoint());
  ASSERT_TRUE(publisher.wait_for_subscribers(1, kPatience));
  publisher.publish({{"type", "run_start"}});
  auto m = subscriber.receive(kPatience);
  ASSERT_TRUE(m);
  EXPECT_EQ((*m)["type"], "run_start");
}

// ---- endpoints ----

std::string endpoint_error(const rig::telemetry::TelemetryEndpoints& e) {
  try {
    rig::telemetry::validate_endpoints(e);
  } catch (const rig::telemetry::EndpointError& error) {
    return error.what();
  }
  return "";
}

TEST(Endpoints, DefaultsAreLoopbackAndValid) {
  EXPECT_EQ(endpoint_error({}), "");
}

TEST(Endpoints, LoopbackFormsAreAccepted) {
  for (const std::string e : {"tcp://127.0.0.1:5556", "tcp://127.10.20.30:1", "tcp://[::1]:5556",
                              "tcp://localhost:*", "ipc:///tmp/rig-telemetry", "inproc://rig"}) {
    EXPECT_TRUE(rig::telemetry::is_loopback_endpoint(e)) << e;
    EXPECT_NO_THROW(rig::telemetry::validate_endpoint(e, false, "publish endpoint")) << e;
  }
}

TEST(Endpoints, NonLoopbackIsRefusedWithoutAllowRemoteNamingTheEndpoint) {
  for (const std::string e : {"tcp://*:5556", "tcp://0.0.0.0:5556", "tcp://192.168.1.20:5556",
                              "tcp://eth0:5556", "tcp://128.0.0.1:5556", "tcp://127.0.0:5556"}) {
    rig::telemetry::TelemetryEndpoints endpoints;
    endpoints.control = e;
    const std::string message = endpoint_error(endpoints);
    EXPECT_NE(message.find("control endpoint \"" + e + "\""), std::string::npos) << message;
    EXPECT_NE(message.find("beyond this machine"), std::string::npos) << message;
    endpoints.allow_remote = true;
    EXPECT_EQ(endpoint_error(endpoints), "") << e;
  }
}

TEST(Endpoints, MalformedEndpointsAreRefusedSayingWhatWasExpected) {
  for (const std::string e :
       {"127.0.0.1:5556", "tcp://127.0.0.1", "tcp://127.0.0.1:0", "tcp://127.0.0.1:65536",
        "tcp://127.0.0.1:port", "tcp://:5556", "tcp://::1:5556", "tcp://[::1]5556", "udp://x:1",
        "ipc://", "inproc://"}) {
    rig::telemetry::TelemetryEndpoints endpoints;
    endpoints.publish = e;
    endpoints.allow_remote = true;  // malformed is refused even then
    const std::string message = endpoint_error(endpoints);
    EXPECT_NE(message.find("publish endpoint \"" + e + "\" is malformed"), std::string::npos)
        << message;
    EXPECT_NE(message.find("expected tcp://HOST:PORT"), std::string::npos) << message;
  }
}

TEST(Endpoints, PublishAndControlMustDiffer) {
  rig::telemetry::TelemetryEndpoints endpoints;
  endpoints.control = endpoints.publish;
  EXPECT_NE(endpoint_error(endpoints).find("both \"tcp://127.0.0.1:5556\""), std::string::npos);
}

// libzmq unlinks whatever is at an ipc:// path before binding: a path that
// exists and is not a socket is refused, and the file is left as it was.
TEST(Endpoints, IpcPathOverAnExistingFileIsRefusedAndTheFileKept) {
  const std::string path = ::testing::TempDir() + "rig-ipc-existing-file";
  { std::ofstream(path) << "precious"; }
  const std::string endpoint = "ipc://" + path;
  EXPECT_THROW(rig::telemetry::validate_endpoint(endpoint, false, "publish endpoint"),
               rig::telemetry::EndpointError);
  try {
    rig::telemetry::TelemetryPublisher publisher(endpoint);
    FAIL() << "bound over " << path;
  } catch (const rig::telemetry::EndpointError& e) {
    EXPECT_NE(std::string(e.what()).find("exists and is not a socket"), std::string::npos)
        << e.what();
  }
  rig::telemetry::ControlState state;
  EXPECT_THROW(rig::telemetry::ControlServer(endpoint, state, [] { return json::object(); }),
               rig::telemetry::EndpointError);
  std::ifstream in(path);
  std::string text;
  in >> text;
  EXPECT_EQ(text, "precious");
  std::remove(path.c_str());
}

// A Unix socket's path holds 107 bytes and its NUL: a longer ipc:// path is
// refused when checked, not when bound after the sweep file was accepted.
TEST(Endpoints, IpcPathLongerThanASocketPathIsRefused) {
  const std::string fits = "ipc:///tmp/" + std::string(107 - 5, 'p');
  EXPECT_NO_THROW(rig::telemetry::validate_endpoint(fits, false, "publish endpoint"));
  try {
    rig::telemetry::validate_endpoint(fits + "p", false, "publish endpoint");
    FAIL() << "accepted a 108-byte path";
  } catch (const rig::telemetry::EndpointError& e) {
    EXPECT_NE(std::string(e.what()).find("the path is 108 bytes long: expected at most 107"),
              std::string::npos)
        << e.what();
  }
}

// Binding creates the socket in the path's folder: a folder that does not
// exist (or is a file) is refused when checked, naming it (the mutation test
// found the sweep file taken, then exit 1 at the bind).
TEST(Endpoints, IpcPathInAFolderThatDoesNotExistIsRefused) {
  const std::string missing = ::testing::TempDir() + "rig-no-such-folder/";
  EXPECT_NO_THROW(rig::telemetry::validate_endpoint("ipc://" + ::testing::TempDir() + "rig-sock",
                                                    false, "publish endpoint"));
  try {
    rig::telemetry::validate_endpoint("ipc://" + missing + "sock", false, "publish endpoint");
    FAIL() << "accepted a socket in " << missing;
  } catch (const rig::telemetry::EndpointError& e) {
    EXPECT_NE(std::string(e.what()).find("\"" + missing + "\" is not an existing folder"),
              std::string::npos)
        << e.what();
  }
}

// A socket left by an earlier run is bound over as before.
TEST(Endpoints, IpcPathOfAnEarlierSocketIsReused) {
  const std::string path = ::testing::TempDir() + "rig-ipc-reused";
  std::remove(path.c_str());
  const std::string endpoint = "ipc://" + path;
  {
    // A socket file whose process is gone, as a killed sweep leaves it.
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::snprintf(address.sun_path, sizeof address.sun_path, "%s", path.c_str());
    ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
    ::close(fd);
  }
  EXPECT_NO_THROW(rig::telemetry::validate_endpoint(endpoint, false, "publish endpoint"));
  rig::telemetry::TelemetryPublisher second(endpoint);
  EXPECT_EQ(second.endpoint(), endpoint);
}

TEST(Endpoints, EndpointErrorIsATelemetryError) {
  rig::telemetry::TelemetryEndpoints endpoints;
  endpoints.publish = "nonsense";
  EXPECT_THROW(rig::telemetry::validate_endpoints(endpoints), rig::telemetry::TelemetryError);
}

// ---- control ----

TEST(ControlState, WaitWhilePausedReturnsAtOnceUnlessPaused) {
  rig::telemetry::ControlState state;
  EXPECT_TRUE(state.wait_while_paused());
  state.request_abort("operator");
  EXPECT_FALSE(state.wait_while_paused());
  EXPECT_EQ(state.abort_reason(), "operator");
  state.request_abort("second reason");
  EXPECT_EQ(state.abort_reason(), "operator") << "the first reason is kept";
}

// Runs `body` on a thread standing in for the controller. When it goes out
// of scope (also after a failed assertion) it aborts the sweep, so a body
// blocked in wait_while_paused() ends, and joins.
class ControllerThread {
 public:
  template <class Body>
  ControllerThread(rig::telemetry::ControlState& state, Body body) : state_(state), thread_(body) {}
  ~ControllerThread() {
    state_.request_abort("end of test");
    join();
  }
  void join() {
    if (thread_.joinable()) thread_.join();
  }

 private:
  rig::telemetry::ControlState& state_;
  std::thread thread_;
};

TEST(ControlState, ControllerPauseHoldsUntilResume) {
  rig::telemetry::ControlState state;
  state.set_paused_by_controller(true);
  EXPECT_TRUE(state.pause_requested());
  std::atomic<int> result{-1};
  ControllerThread sweep(state, [&] { result = state.wait_while_paused() ? 1 : 0; });
  ASSERT_TRUE(eventually([&] { return state.paused(); }));
  EXPECT_EQ(result, -1);
  state.request_resume();
  sweep.join();
  EXPECT_EQ(result, 1);
  EXPECT_FALSE(state.paused_by_controller());
  EXPECT_FALSE(state.paused());
}

// A fake sweep loop: one step per "position" (1 ms of pretend work),
// wait_while_paused() between steps as the controller does.
auto fake_sweep(rig::telemetry::ControlState& state, std::atomic<int>& steps) {
  return [&state, &steps] {
    while (state.wait_while_paused()) {
      ++steps;
      std::this_thread::sleep_for(1ms);  // the position's work, not synchronisation
    }
  };
}

class Control : public ::testing::Test {
 protected:
  rig::telemetry::ControlState state;
  std::atomic<int> status_calls{0};
  rig::telemetry::ControlServer server{"tcp://127.0.0.1:*", state, [this] {
                                         ++status_calls;
                                         return json{
                                             {"state", state.paused() ? "paused" : "running"},
                                             {"pause_requested", state.pause_requested()}};
                                       }};
  json send(const std::string& command, const std::string& reason = "") {
    return rig::telemetry::send_control(server.endpoint(), command, kPatience, reason);
  }
};

TEST_F(Control, StatusRepliesWithTheStatusFunctionsObject) {
  const json reply = send("status");
  EXPECT_EQ(reply["ok"], true);
  EXPECT_EQ(reply["command"], "status");
  EXPECT_EQ(reply["status"]["state"], "running");
  EXPECT_EQ(status_calls, 1);
}

TEST_F(Control, PauseAndResumeActBeforeTheStatusIsTaken) {
  EXPECT_EQ(send("pause")["status"]["pause_requested"], true);
  EXPECT_TRUE(state.pause_requested());
  EXPECT_EQ(send("resume")["status"]["pause_requested"], false);
  EXPECT_FALSE(state.pause_requested());
}

TEST_F(Control, PausedSweepStopsAdvancingAndContinuesAfterResume) {
  std::atomic<int> steps{0};
  ControllerThread sweep(state, fake_sweep(state, steps));
  ASSERT_TRUE(eventually([&] { return steps >= 3; }));
  ASSERT_EQ(send("pause")["ok"], true);
  ASSERT_TRUE(eventually([&] { return state.paused(); }));
  const int held_at = steps;
  // Several round trips through the socket while held: the loop is blocked
  // inside wait_while_paused, so its count cannot move.
  for (int i = 0; i < 5; ++i)
    EXPECT_EQ(send("status")["status"]["state"], "paused");
  EXPECT_EQ(steps, held_at);
  ASSERT_EQ(send("resume")["ok"], true);
  EXPECT_TRUE(eventually([&] { return steps > held_at + 2; }));
  EXPECT_EQ(send("abort")["ok"], true);
  sweep.join();
  EXPECT_EQ(state.abort_reason(), "abort requested over the control socket");
}

TEST_F(Control, AbortWhilePausedEndsTheWaitWithFalseAndKeepsTheReason) {
  send("pause");
  std::atomic<int> result{-1};
  ControllerThread sweep(state, [&] { result = state.wait_while_paused() ? 1 : 0; });
  ASSERT_TRUE(eventually([&] { return state.paused(); }));
  const json reply = send("abort", "lens cap on");
  sweep.join();
  EXPECT_EQ(reply["ok"], true);
  EXPECT_EQ(result, 0);
  EXPECT_TRUE(state.abort_requested());
  EXPECT_EQ(state.abort_reason(), "lens cap on");
}

TEST_F(Control, UnknownCommandIsRefusedListingTheCommands) {
  const json reply = send("jump");
  EXPECT_EQ(reply["ok"], false);
  EXPECT_EQ(reply["error"], "unknown command \"jump\"; expected status, pause, resume or abort");
  EXPECT_FALSE(state.pause_requested());
  EXPECT_FALSE(state.abort_requested());
}

// A REQ client of its own that sends `text` as given (send_control always
// sends JSON), as a client in another language might.
json raw_request(const std::string& endpoint, const std::string& text,
                 std::chrono::milliseconds patience = kPatience) {
  zmq::context_t context;
  zmq::socket_t socket(context, zmq::socket_type::req);
  socket.set(zmq::sockopt::linger, 0);
  socket.set(zmq::sockopt::rcvtimeo, static_cast<int>(patience.count()));
  socket.connect(endpoint);
  socket.send(zmq::buffer(text), zmq::send_flags::none);
  zmq::message_t reply;
  if (!socket.recv(reply)) return json{{"ok", "no reply"}};
  return json::parse(reply.to_string());
}

TEST_F(Control, AcceptsBareWordsAndRejectsMalformedJson) {
  EXPECT_EQ(raw_request(server.endpoint(), "pause\n")["ok"], true);
  EXPECT_TRUE(state.pause_requested());
  const json bad = raw_request(server.endpoint(), "{\"command\": ");
  EXPECT_EQ(bad["ok"], false);
  EXPECT_NE(bad["error"].get<std::string>().find("not valid JSON"), std::string::npos);
  const json no_command = raw_request(server.endpoint(), "{\"reason\": \"x\"}");
  EXPECT_EQ(no_command["ok"], false);
  EXPECT_NE(no_command["error"].get<std::string>().find("no \"command\""), std::string::npos);
}

// {"a": [[[...]]]} nested 200,000 deep: before the bounded parser, the
// reply's "request <dump>" recursed once per level and killed the sweep.
TEST_F(Control, DeeplyNestedRequestIsRefusedAndTheServerKeepsAnswering) {
  constexpr int kDepth = 200000;
  const std::string request =
      "{\"a\": " + std::string(kDepth, '[') + std::string(kDepth, ']') + "}";
  // 400 kB: beyond the request's size bound (64 KiB), so libzmq drops the
  // peer before anything is parsed: no reply (a reply takes well under 1 s
  // on loopback, so 1 s of silence is the drop)...
  EXPECT_EQ(raw_request(server.endpoint(), request, 1000ms)["ok"], "no reply");
  // ...and within it, the depth bound (8 levels) refuses it by name.
  constexpr int kSmallDepth = 20000;
  const std::string small =
      "{\"a\": " + std::string(kSmallDepth, '[') + std::string(kSmallDepth, ']') + "}";
  const json reply = raw_request(server.endpoint(), small);
  EXPECT_EQ(reply["ok"], false);
  const std::string error = reply["error"].get<std::string>();
  EXPECT_NE(error.find("request: nests arrays or objects more than 8 levels deep"),
            std::string::npos)
      << error;
  EXPECT_FALSE(state.abort_requested());
  EXPECT_EQ(send("status")["ok"], true) << "the server still answers";
}

// An error message quotes at most an excerpt of a request, however long.
TEST_F(Control, ALongCommandIsQuotedAsAnExcerpt) {
  const std::string word(60000, 'x');
  const json reply = raw_request(server.endpoint(), "{\"command\": \"" + word + "\"}");
  EXPECT_EQ(reply["ok"], false);
  EXPECT_LT(reply["error"].get<std::string>().size(), 300u) << "80 characters quoted, plus text";
}

TEST_F(Control, ServerKeepsAnsweringAfterAStatusFunctionThrows) {
  rig::telemetry::ControlState other;
  rig::telemetry::ControlServer failing(
      "tcp://127.0.0.1:*", other, []() -> json { throw std::runtime_error("database locked"); });
  const json reply = rig::telemetry::send_control(failing.endpoint(), "pause", kPatience);
  EXPECT_EQ(reply["ok"], false);
  EXPECT_NE(reply["error"].get<std::string>().find("database locked"), std::string::npos);
  EXPECT_TRUE(other.pause_requested()) << "the pause itself was done";
  EXPECT_EQ(rig::telemetry::send_control(failing.endpoint(), "status", kPatience)["ok"], false);
}

TEST(ControlServer, BusyPortThrowsNamingTheEndpoint) {
  rig::telemetry::ControlState state;
  rig::telemetry::ControlServer first("tcp://127.0.0.1:*", state, [] { return json::object(); });
  try {
    rig::telemetry::ControlServer second(first.endpoint(), state, [] { return json::object(); });
    FAIL() << "bound twice to " << first.endpoint();
  } catch (const rig::telemetry::TelemetryError& e) {
    EXPECT_NE(std::string(e.what()).find(first.endpoint()), std::string::npos) << e.what();
  }
}

TEST(SendControl, TimesOutWhenNothingListensNamingTheEndpoint) {
  std::string endpoint;
  {
    // A port that was free a moment ago; nothing answers REQ on it now.
    rig::telemetry::TelemetryPublisher probe("tcp://127.0.0.1:*");
    endpoint = probe.endpoint();
  }
  const auto start = std::chrono::steady_clock::now();
  try {
    rig::telemetry::send_control(endpoint, "status", 50ms);
    FAIL() << "answered from " << endpoint;
  } catch (const rig::telemetry::TelemetryError& e) {
    EXPECT_EQ(std::string(e.what()), "no sweep answering at " + endpoint + " within 50 ms");
  }
  EXPECT_GE(std::chrono::steady_clock::now() - start, 50ms);
}

}  // namespace
