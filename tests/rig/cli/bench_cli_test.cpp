// The `rig sim bench` and `rig bench` commands, run as a person would: the
// simulated bench in its own process, driven by `rig bench`, stopped by
// SIGINT or SIGTERM.
#include <gtest/gtest.h>

#include <csignal>
#include <memory>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "motion/drive_profile.hpp"
#include "motion/errors.hpp"
#include "motion/modbus_bench.hpp"

namespace {

using namespace std::chrono_literals;
using rig_test::ChildProcess;

const std::string kRig = std::string(RIG_BINARY_DIR) + "/bin/rig";
const std::string kSim = std::string(RIG_SOURCE_DIR) + "/config/benches/sim.toml";

// The waits for `rig sim bench` to print its port or to exit return as soon as
// it does (well under a second); they only bound a broken test, with room for
// a loaded host or a sanitizer build.
constexpr auto kProcessWait = 30s;

// Starts `rig sim bench` on an ephemeral port and returns the port it prints.
int start_sim(ChildProcess& sim) {
  const auto line = sim.read_line(kProcessWait);
  EXPECT_TRUE(line.has_value()) << "rig sim bench printed nothing";
  std::smatch m;
  const std::string text = line.value_or("");
  EXPECT_TRUE(std::regex_search(text, m, std::regex(R"(modbus-tcp://127\.0\.0\.1:(\d+))"))) << text;
  return m.empty() ? 0 : std::stoi(m[1]);
}

std::string rig_bench(const std::string& args, int port, int* status) {
  return rig_test::run_command(kRig + " bench " + args + " --bench modbus-tcp://127.0.0.1:" +
                                   std::to_string(port) + " --profile " + kSim + " 2>&1",
                               status);
}

TEST(RigSimBench, ServesUntilSigtermAndThenExitsCleanly) {
  ChildProcess sim({kRig, "sim", "bench", "--port", "0", "--config", kSim, "--time-scale", "20"});
  const int port = start_sim(sim);
  ASSERT_GT(port, 0);
  motion::ModbusBench bench(
      motion::BenchUrl::parse("modbus-tcp://127.0.0.1:" + std::to_string(port)),
      motion::load_drive_profile(kSim));
  EXPECT_FALSE(bench.status().homed);
  EXPECT_EQ(sim.signal_and_wait(SIGTERM, kProcessWait), 0);
}

TEST(RigSimBench, ExitsCleanlyOnSigint) {
  ChildProcess sim({kRig, "sim", "bench", "--port", "0", "--config", kSim});
  ASSERT_GT(start_sim(sim), 0);
  EXPECT_EQ(sim.signal_and_wait(SIGINT, kProcessWait), 0);
}

TEST(RigSimBench, KilledAndRestartedMidMoveMakesTheDriverRaise) {
  // The literal case: the simulated bench's process is SIGKILLed mid-move and
  // a new one starts on the same port, not homed. The driver must reconnect,
  // re-read the state and raise rather than report the move as done.
  auto sim = std::make_unique<ChildProcess>(std::vector<std::string>{
      kRig, "sim", "bench", "--port", "0", "--config", kSim, "--time-scale", "5"});
  const int port = start_sim(*sim);
  ASSERT_GT(port, 0);
  motion::DriveProfile profile = motion::load_drive_profile(kSim);
  profile.timing.reconnect_timeout_ms = 3000;  // covers the restart of a process
  motion::ModbusBench bench(
      motion::BenchUrl::parse("modbus-tcp://127.0.0.1:" + std::to_string(port)), profile);
  bench.home();
  bench.wait_settled(5s);
  bench.move_to(100, 50);  // 2 s simulated, 0.4 s wall at time scale 5
  std::this_thread::sleep_for(50ms);
  EXPECT_EQ(sim->signal_and_wait(SIGKILL, kProcessWait), 128 + SIGKILL);
  sim = std::make_unique<ChildProcess>(std::vector<std::string>{
      kRig, "sim", "bench", "--port", std::to_string(port), "--config", kSim});
  ASSERT_EQ(start_sim(*sim), port);
  try {
    bench.wait_settled(5s);
    FAIL() << "the move was reported settled by a restarted bench";
  } catch (const motion::BenchLinkError& e) {
    EXPECT_NE(std::string(e.what()).find("no longer homed"), std::string::npos) << e.what();
  }
}

TEST(RigBench, HomesMovesAndReportsTheSimulatedBench) {
  ChildProcess sim({kRig, "sim", "bench", "--port", "0", "--config", kSim, "--time-scale", "20"});
  const int port = start_sim(sim);
  int status = -1;
  rig_bench("home", port, &status);
  EXPECT_EQ(status, 0);
  const std::string out = rig_bench("move 12.5 7.25", port, &status);
  EXPECT_EQ(status, 0) << out;
  EXPECT_NE(out.find("position x 12.5000 mm, y 7.2500 mm"), std::string::npos) << out;
  rig_bench("jog 0.5 0", port, &status);
  EXPECT_EQ(status, 0);
  EXPECT_NE(rig_bench("status", port, &status).find("position x 13.0000 mm"), std::string::npos);
}

TEST(RigBench, MoveOutsideTheSoftLimitsExitsWithBadInput) {
  ChildProcess sim({kRig, "sim", "bench", "--port", "0", "--config", kSim, "--time-scale", "20"});
  const int port = start_sim(sim);
  int status = -1;
  const std::string out = rig_bench("move 1000 0", port, &status);
  EXPECT_EQ(status, 2) << out;
  EXPECT_NE(out.find("refused, nothing sent"), std::string::npos) << out;
}

// A speed that is not a positive finite number, or that rounds to 0 in the
// drive's units (the simulated drive's speed register is in whole mm/s, so
// 0.4 mm/s is written as 0), is refused before anything is sent: exit 2, the
// speed named, and the bench still where it was.
TEST(RigBench, SpeedThatIsNotPositiveOrRoundsToZeroIsRefused) {
  ChildProcess sim({kRig, "sim", "bench", "--port", "0", "--config", kSim, "--time-scale", "20"});
  const int port = start_sim(sim);
  int status = -1;
  rig_bench("home", port, &status);
  ASSERT_EQ(status, 0);
  for (const std::string speed : {"0", "-5", "nan", "inf", "0.4"}) {
    const std::string out = rig_bench("move 45 15 --speed=" + speed, port, &status);
    EXPECT_EQ(status, 2) << speed << ": " << out;
    EXPECT_NE(out.find("rig bench: speed"), std::string::npos) << speed << ": " << out;
  }
  EXPECT_NE(rig_bench("move 45 15 --speed=0.4", port, &status).find("rounds to 0"),
            std::string::npos);
  const std::string out = rig_bench("status", port, &status);
  EXPECT_NE(out.find("position x 0.0000 mm, y 0.0000 mm"), std::string::npos) << out;
  // The smallest speed the drive takes (0.5 mm/s rounds to 1) moves.
  EXPECT_NE(rig_bench("jog 0.5 0 --speed=0.5", port, &status).find("position x 0.5000 mm"),
            std::string::npos);
  EXPECT_EQ(status, 0);
}

TEST(RigBench, MoveBeforeHomingFailsWithTheAlarmsMeaning) {
  ChildProcess sim({kRig, "sim", "bench", "--port", "0", "--config", kSim, "--time-scale", "20"});
  const int port = start_sim(sim);
  int status = -1;
  const std::string out = rig_bench("move 1 1", port, &status);
  EXPECT_EQ(status, 1) << out;
  EXPECT_NE(out.find("alarm 3 (not homed: home before moving)"), std::string::npos) << out;
  rig_bench("reset", port, &status);
  EXPECT_EQ(status, 0);
}

}  // namespace
