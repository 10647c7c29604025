// `rig monitor` and `rig ctl` run as a user would, against a publisher and a
// control server started in this test process (no controller, no bench).
#include <gtest/gtest.h>

#include <rig_command.hpp>
#include <sstream>
#include <thread>
#include <vector>

#include "rig/telemetry/telemetry.hpp"

namespace {

using namespace std::chrono_literals;
using nlohmann::json;

// Only reached when something is broken (a rig process that never starts or
// never subscribes); a healthy one subscribes within tens of milliseconds.
constexpr auto kPatience = 20s;
const std::string kMonitorTimeout = " --timeout-s 20";

std::vector<json> a_run(const std::string& stop_status, int positions) {
  std::vector<json> run;
  run.push_back({{"type", "run_start"},
                 {"run_id", 7},
                 {"database", "/tmp/run.db"},
                 {"plan_size", positions},
                 {"first_index", 0},
                 {"resumed", false},
                 {"solvers", {"lm"}},
                 {"frames_per_position", 3},
                 {"sweep_file", "config/sweeps/ci.toml"}});
  for (int i = 0; i < positions; ++i)
    run.push_back({{"type", "position"},
                   {"run_id", 7},
                   {"plan_index", i},
                   {"completed", i + 1},
                   {"plan_size", positions},
                   {"status", "ok"},
                   {"measured", {{"x_mm", 10.0 * i}, {"y_mm", 5.0}}},
                   {"true_distance_m", 0.5 + 0.01 * i},
                   {"markers_detected", 4},
                   {"estimates",
                    {{{"solver", "lm"},
                      {"scope", "target"},
                      {"distance_error_m", 0.001},
                      {"converged", true}}}},
                   {"elapsed_s", 1.0 + i}});
  run.push_back({{"type", "run_stop"},
                 {"run_id", 7},
                 {"status", stop_status},
                 {"reason", ""},
                 {"positions_ok", positions},
                 {"positions_failed", 0},
                 {"plan_size", positions},
                 {"elapsed_s", 1.0 + positions}});
  return run;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    lines.push_back(line);
  return lines;
}

// Runs `rig monitor ARGS` against a fresh publisher and, once the monitor has
// subscribed (the handshake), publishes `messages`.
rig_test::RigRun monitor(const std::string& args, const std::vector<json>& messages) {
  rig::telemetry::TelemetryPublisher publisher("tcp://127.0.0.1:*");
  rig_test::RigRun run;
  std::thread rig_process(
      [&] { run = rig_test::run_rig("monitor --endpoint " + publisher.endpoint() + " " + args); });
  const bool subscribed = publisher.wait_for_subscribers(1, kPatience);
  if (subscribed)
    for (const auto& m : messages)
      publisher.publish(m);
  rig_process.join();
  EXPECT_TRUE(subscribed) << "rig monitor never subscribed: " << run.err;
  return run;
}

TEST(RigMonitor, UntilStopPrintsTheRunsLinesAndExitsZeroWhenCompleted) {
  const auto r = monitor("--until-stop" + kMonitorTimeout, a_run("completed", 3));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const auto lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 5u) << r.out;
  EXPECT_EQ(lines[0].rfind("run 7 started: 3 positions", 0), 0u) << lines[0];
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(lines[1 + i].rfind(
                  "position " + std::to_string(i) + " (" + std::to_string(i + 1) + "/3) ok", 0),
              0u)
        << lines[1 + i];
  EXPECT_EQ(lines[4], "run 7 completed: 3 ok, 0 failed of 3 positions in 4s");
}

TEST(RigMonitor, UntilStopExitsOneWhenTheRunWasAborted) {
  const auto r = monitor("--until-stop" + kMonitorTimeout, a_run("aborted", 1));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.out.find("run 7 aborted"), std::string::npos) << r.out;
}

TEST(RigMonitor, JsonPrintsEveryMessageAsReceived) {
  const auto run = a_run("completed", 4);
  const auto r = monitor("--until-stop --json" + kMonitorTimeout, run);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const auto lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), run.size()) << r.out;
  for (size_t i = 0; i < run.size(); ++i)
    EXPECT_EQ(json::parse(lines[i]), run[i]) << lines[i];
}

TEST(RigMonitor, TimesOutWhenNothingArrives) {
  rig::telemetry::TelemetryPublisher silent("tcp://127.0.0.1:*");
  const auto r =
      rig_test::run_rig("monitor --until-stop --timeout-s 0.2 --endpoint " + silent.endpoint());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no telemetry from " + silent.endpoint() + " within 0.2 s"),
            std::string::npos)
      << r.err;
}

TEST(RigMonitor, RefusesAMalformedEndpointAsBadInput) {
  const auto r = rig_test::run_rig("monitor --endpoint 127.0.0.1:5556 --timeout-s 1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--endpoint \"127.0.0.1:5556\" is malformed"), std::string::npos) << r.err;
}

TEST(RigMonitor, HelpHasAnExample) {
  const auto r = rig_test::run_rig("monitor --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("Example: rig monitor"), std::string::npos) << r.out;
}

// ---- rig ctl ----

class RigCtl : public ::testing::Test {
 protected:
  rig::telemetry::ControlState state;
  rig::telemetry::ControlServer server{
      "tcp://127.0.0.1:*", state, [this] {
        return json{{"state", state.pause_requested() ? "paused" : "running"},
                    {"run_id", 7},
                    {"completed", 13},
                    {"plan_size", 201}};
      }};
  rig_test::RigRun ctl(const std::string& args) {
    return rig_test::run_rig("ctl " + args + " --endpoint " + server.endpoint());
  }
};

TEST_F(RigCtl, StatusPrintsOneLineForPeopleAndTheWholeReplyWithJson) {
  const auto r = ctl("status");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out,
            "state running, run 7: 13 of 201 positions stored (6.5 %), at plan index -, ETA --\n");
  const auto j = ctl("status --json");
  EXPECT_EQ(j.exit_code, 0) << j.err;
  EXPECT_EQ(json::parse(j.out)["status"],
            (json{{"state", "running"}, {"run_id", 7}, {"completed", 13}, {"plan_size", 201}}));
}

TEST_F(RigCtl, PauseResumeAndAbortActOnTheSweep) {
  auto r = ctl("pause");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(state.pause_requested());
  EXPECT_NE(r.out.find("pause requested"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("state paused"), std::string::npos) << r.out;
  r = ctl("resume");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(state.pause_requested());
  r = ctl("abort --reason \"lens cap on\"");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(state.abort_requested());
  EXPECT_EQ(state.abort_reason(), "lens cap on");
}

TEST_F(RigCtl, JsonPrintsTheWholeReply) {
  const auto r = ctl("pause --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const json reply = json::parse(r.out);
  EXPECT_EQ(reply["ok"], true);
  EXPECT_EQ(reply["command"], "pause");
  EXPECT_EQ(reply["status"]["state"], "paused");
}

TEST_F(RigCtl, UnknownCommandIsBadInputAndSendsNothing) {
  const auto r = ctl("jump");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("jump not in {status,pause,resume,abort}"), std::string::npos) << r.err;
  EXPECT_FALSE(state.pause_requested());
}

TEST(RigCtlAlone, SaysNoSweepIsAnsweringWhenNothingListens) {
  std::string endpoint;
  {
    rig::telemetry::TelemetryPublisher probe("tcp://127.0.0.1:*");  // a port free a moment ago
    endpoint = probe.endpoint();
  }
  const auto r = rig_test::run_rig("ctl status --timeout-ms 200 --endpoint " + endpoint);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no sweep answering at " + endpoint + " within 200 ms"), std::string::npos)
      << r.err;
}

TEST(RigCtlAlone, ARefusalExitsOneWithTheSweepsReason) {
  rig::telemetry::ControlState state;
  rig::telemetry::ControlServer server(
      "tcp://127.0.0.1:*", state, []() -> json { throw std::runtime_error("database locked"); });
  const auto r = rig_test::run_rig("ctl status --endpoint " + server.endpoint());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("database locked"), std::string::npos) << r.err;
}

TEST(RigCtlAlone, HelpHasAnExample) {
  const auto r = rig_test::run_rig("ctl --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("Example: rig ctl pause"), std::string::npos) << r.out;
}

}  // namespace
