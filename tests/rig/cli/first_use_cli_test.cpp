// What a new user meets when a part of the rig is not there or is taken:
// each error, through the built programs, names the likely cause and the
// fix, with the exit status of rig/cli/src/exit_codes.hpp (1 a failure while
// running, 2 bad input). The GigE cases hold the ctest RESOURCE_LOCK
// gige_loopback: one camera per address and port 3956.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <string>

#include "child_process.hpp"
#include "rig_command.hpp"
#include "vision/gige_source.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using rig_test::ChildProcess;
using rig_test::run_rig;

const std::string kRig = std::string(RIG_BINARY_DIR) + "/bin/rig";
const std::string kConfig = std::string(RIG_SOURCE_DIR) + "/config";
// `rig sim` prints its lines within a second; this bounds a broken one.
constexpr auto kProcessWait = 30s;

// A loopback TCP socket bound to an ephemeral port, listening or not.
class LoopbackPort {
 public:
  explicit LoopbackPort(bool listening) {
    fd_ = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in sa{};
    sa.sin_family = AF_INET;
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(bind(fd_, reinterpret_cast<sockaddr*>(&sa), sizeof sa), 0);
    if (listening) {
      EXPECT_EQ(listen(fd_, 1), 0);
    }
    socklen_t len = sizeof sa;
    getsockname(fd_, reinterpret_cast<sockaddr*>(&sa), &len);
    port_ = ntohs(sa.sin_port);
  }
  ~LoopbackPort() { close(fd_); }
  int port() const { return port_; }

 private:
  int fd_ = -1;
  int port_ = 0;
};

class FirstUse : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "rig-first-use-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  // config/sim.toml with absolute paths, a free bench port and `camera_address`.
  std::string sim_rig_file(const std::string& camera_address) {
    std::ifstream in(kConfig + "/sim.toml");
    std::string text((std::istreambuf_iterator<char>(in)), {});
    text = std::regex_replace(text, std::regex("\"(benches|rigs|targets|realism)/"),
                              "\"" + kConfig + "/$1/");
    text = std::regex_replace(text, std::regex("port = 1502"), "port = 0");
    text = std::regex_replace(text, std::regex("address = \"127.0.0.1\""),
                              "address = \"" + camera_address + "\"");
    return write("sim.toml", text);
  }
  // config/sweeps/smoke.toml with absolute paths and the given telemetry publish endpoint.
  std::string sweep_file(const std::string& publish) {
    std::ifstream in(kConfig + "/sweeps/smoke.toml");
    std::string text((std::istreambuf_iterator<char>(in)), {});
    text = std::regex_replace(text, std::regex("\"\\.\\./"), "\"" + kConfig + "/");
    text += "\n[telemetry]\npublish = \"" + publish + "\"\ncontrol = \"ipc://" +
            (dir_ / "control").string() + "\"\n";
    return write("sweep.toml", text);
  }
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  static void expect_has(const std::string& text, const std::string& part) {
    EXPECT_NE(text.find(part), std::string::npos) << "missing \"" << part << "\" in: " << text;
  }

  fs::path dir_;
};

TEST_F(FirstUse, BenchWithNothingListeningAsksWhetherTheSimulatedRigRuns) {
  const LoopbackPort bound_not_listening(false);  // a connect is refused, deterministically
  const std::string port = std::to_string(bound_not_listening.port());
  const rig_test::RigRun r = run_rig("bench status --bench modbus-tcp://127.0.0.1:" + port +
                                     " --profile " + kConfig + "/benches/sim.toml");
  EXPECT_EQ(r.exit_code, 1);
  expect_has(r.err, "nothing listens at 127.0.0.1:" + port);
  expect_has(r.err, "is `rig sim` (or `rig sim bench`) running?");
}

TEST_F(FirstUse, RigSimOutsideTheRepositoryIsBadInputNamingThePathAndConfig) {
  int status = -1;
  const std::string out =
      rig_test::run_command("cd " + dir_.string() + " && " + kRig + " sim 2>&1", &status);
  EXPECT_EQ(status, 2) << out;
  expect_has(out, "config/sim.toml not found (looked for " + (dir_ / "config/sim.toml").string());
  expect_has(out, "--config FILE");
}

TEST_F(FirstUse, SimCameraOnAnAddressOfNoInterfaceSaysHowToAddIt) {
  // 127.0.0.2 answers on Linux's lo (127.0.0.0/8) but is no interface's own
  // address, which Aravis needs to serve a camera.
  int status = -1;
  const std::string out =
      rig_test::run_command(kRig + " sim --config " + sim_rig_file("127.0.0.2") + " 2>&1", &status);
  EXPECT_EQ(status, 1) << out;
  expect_has(out,
             "camera.address \"127.0.0.2\" is not the address (or name) of a network "
             "interface of this machine");
  expect_has(out, "`sudo ip addr add 127.0.0.2/8 dev lo`");
}

TEST_F(FirstUse, SecondSimRigNamesTheCameraPortTheFirstHolds) {
  ChildProcess first({kRig, "sim", "--config", sim_rig_file("127.0.0.1")});
  for (int i = 0; i < 2; ++i)
    ASSERT_TRUE(first.read_line(kProcessWait)) << "rig sim did not start";
  int status = -1;
  const std::string out = rig_test::run_command(
      kRig + " sim --config " + (dir_ / "sim.toml").string() + " 2>&1", &status);
  EXPECT_EQ(status, 1) << out;
  expect_has(out, "GigE Vision control port 127.0.0.1:3956 is taken");
  expect_has(out, "most likely another `rig sim`");
}

TEST_F(FirstUse, SweepWithNoCameraAsksWhetherTheSimulatedRigRuns) {
  const rig_test::RigRun r = run_rig("sweep " + sweep_file("ipc://" + (dir_ / "publish").string()) +
                                     " --db " + (dir_ / "run.db").string() + " --no-progress");
  EXPECT_EQ(r.exit_code, 1);
  expect_has(r.err, "no GigE Vision camera answers at 127.0.0.1");
  expect_has(r.err, "is `rig sim` running?");
}

TEST_F(FirstUse, CameraHeldByAnotherProcessIsNamedAsTheLikelyCause) {
  ChildProcess sim({kRig, "sim", "--config", sim_rig_file("127.0.0.1")});
  for (int i = 0; i < 2; ++i)
    ASSERT_TRUE(sim.read_line(kProcessWait)) << "rig sim did not start";
  vision::GigeSource holder("127.0.0.1");
  holder.open();  // this process now controls the camera
  const rig_test::RigRun r =
      run_rig("capture --camera gige:127.0.0.1 --frames 1 --out " + (dir_ / "frames").string());
  EXPECT_EQ(r.exit_code, 1);
  expect_has(
      r.err,
      "control of the camera refused: it answers, but another process holds its control channel");
  expect_has(r.err, "another rig sweep or rig capture");
}

TEST_F(FirstUse, TelemetryPortInUseNamesTheKeyAndAnotherSweep) {
  const LoopbackPort taken(true);
  const std::string endpoint = "tcp://127.0.0.1:" + std::to_string(taken.port());
  const rig_test::RigRun r = run_rig("sweep " + sweep_file(endpoint) + " --db " +
                                     (dir_ / "run.db").string() + " --no-progress");
  EXPECT_EQ(r.exit_code, 1);
  expect_has(r.err, "Address already in use");
  expect_has(r.err, "[telemetry] publish = \"" + endpoint + "\"");
  expect_has(r.err, "Another rig sweep may be running");
  EXPECT_FALSE(fs::exists(dir_ / "run.db"));  // stopped before the database
}

// libzmq unlinks whatever is at an ipc:// path before it binds: a publish
// endpoint over a file that is not a socket is bad input naming the key, the
// file is kept and nothing is started.
TEST_F(FirstUse, SweepPublishingOverAnExistingFileIsRefusedAndTheFileKept) {
  const fs::path precious = dir_ / "precious.txt";
  std::ofstream(precious) << "precious";
  const std::string endpoint = "ipc://" + precious.string();
  const rig_test::RigRun r = run_rig("sweep " + sweep_file(endpoint) + " --db " +
                                     (dir_ / "run.db").string() + " --no-progress");
  EXPECT_EQ(r.exit_code, 2);
  expect_has(r.err, "telemetry.publish");
  expect_has(r.err, "exists and is not a socket");
  std::ifstream in(precious);
  std::string text;
  in >> text;
  EXPECT_EQ(text, "precious");
  EXPECT_FALSE(fs::exists(dir_ / "run.db"));
}

}  // namespace
