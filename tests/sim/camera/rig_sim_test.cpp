// `rig sim --config FILE` as a process: it prints the bench URL and the
// camera's id and address, serves frames over GigE Vision, and stops cleanly
// on SIGTERM.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sim/camera/server.hpp"
#include "vision/gige_source.hpp"
#include "vision/image_codecs.hpp"

extern char** environ;

namespace {

using namespace std::chrono_literals;

// Reads the child's stdout until `needle` appears or `timeout` passes.
bool read_until(int fd, std::string& out, const std::string& needle,
                std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (out.find(needle) == std::string::npos) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    pollfd pfd{fd, POLLIN, 0};
    if (poll(&pfd, 1, static_cast<int>(left.count())) <= 0) continue;
    char buffer[512];
    const ssize_t n = read(fd, buffer, sizeof buffer);
    if (n <= 0) return false;
    out.append(buffer, static_cast<size_t>(n));
  }
  return true;
}

TEST(RigSim, ServesBenchAndCameraAndStopsOnSigterm) {
  const std::string rig = std::string(RIG_BINARY_DIR) + "/bin/rig";
  ASSERT_TRUE(std::filesystem::exists(rig)) << rig << " is not built";
  const std::string config_dir = std::string(RIG_SOURCE_DIR) + "/config/";
  const auto config = std::filesystem::temp_directory_path() / "rig_sim_test.toml";
  std::ofstream(config) << "[bench]\nconfig = \"" << config_dir << "benches/sim.toml\"\nport = 0\n"
                        << "[camera]\nrig = \"" << config_dir << "rigs/sim.toml\"\ntarget = \""
                        << config_dir << "targets/paper.toml\"\nserial = \"RIGSIMTEST\"\n";
  int out[2];
  ASSERT_EQ(pipe(out), 0);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
  posix_spawn_file_actions_addclose(&actions, out[0]);
  std::string config_path = config.string();
  // A realism profile given as a FILE, and its hidden truth written out.
  std::string profile = config_dir + "realism/paper.toml";
  std::string truth = (std::filesystem::temp_directory_path() / "rig_sim_test_truth.json").string();
  std::filesystem::remove(truth);
  char* argv[] = {const_cast<char*>(rig.c_str()),
                  const_cast<char*>("sim"),
                  const_cast<char*>("--config"),
                  config_path.data(),
                  const_cast<char*>("--realism"),
                  profile.data(),
                  const_cast<char*>("--write-truth"),
                  truth.data(),
                  nullptr};
  pid_t pid = -1;
  ASSERT_EQ(posix_spawn(&pid, rig.c_str(), &actions, nullptr, argv, environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  close(out[1]);

  // The waits return as soon as the text or the frame is there; they only
  // bound a broken test, with room for a loaded host or a sanitizer build.
  std::string text;
  const bool up = read_until(out[0], text, "), realism profile 'paper'", 30s);
  EXPECT_TRUE(up) << text;
  EXPECT_NE(text.find("modbus-tcp://127.0.0.1:"), std::string::npos) << text;
  EXPECT_NE(text.find("rig-rig-sim-RIGSIMTEST at 127.0.0.1"), std::string::npos) << text;
  if (up) {
    vision::GigeSource camera("127.0.0.1");
    camera.open();
    EXPECT_EQ(camera.device_id(), "rig-rig-sim-RIGSIMTEST");
    camera.trigger();
    EXPECT_EQ(camera.grab(10s).image.cols, 736);
    // The truth is the paper profile's draw: not the nominal camera.
    const nlohmann::json j = nlohmann::json::parse(std::ifstream(truth));
    EXPECT_EQ(j["profile"], "paper");
    EXPECT_NE(j["camera"]["fx"].get<double>(), vision::Camera::paper_default().intrinsics().fx);
    EXPECT_EQ(j["print_scale_error"].get<double>(), 0.003);
  }
  std::filesystem::remove(truth);
  kill(pid, SIGTERM);
  EXPECT_TRUE(read_until(out[0], text, "SIGTERM, stopping", 30s)) << text;
  int status = 0;
  waitpid(pid, &status, 0);
  close(out[0]);
  std::filesystem::remove(config);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
}

}  // namespace

namespace {

// Runs `rig ARGS...` and returns its exit code, stdout and stderr discarded.
int run_rig(std::vector<std::string> args) {
  const std::string rig = std::string(RIG_BINARY_DIR) + "/bin/rig";
  args.insert(args.begin(), rig);
  std::vector<char*> argv;
  for (auto& a : args)
    argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t pid = -1;
  const int spawned = posix_spawn(&pid, rig.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) return -1;
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(RigCapture, SavesTriggeredFramesFromTheSimulatedCamera) {
  auto renderer = std::make_shared<const sim::scene::SceneRenderer>(
      vision::Camera::paper_default(), vision::Target::paper_default(), vision::Codebook());
  sim::camera::CameraServer server(
      renderer, vision::RigGeometry::load(std::string(RIG_SOURCE_DIR) + "/config/rigs/sim.toml"),
      [] { return std::make_pair(300.0, 150.0); });
  server.start();
  const auto out = std::filesystem::temp_directory_path() / "rig_capture_test";
  std::filesystem::remove_all(out);
  // A frame takes milliseconds; a long frame wait keeps a slow host from
  // turning one into a timeout and a retry, which would render a fourth.
  EXPECT_EQ(run_rig({"capture", "--camera", "gige:" + server.address(), "--frames", "3", "--out",
                     out.string(), "--timeout-ms", "10000"}),
            0);
  for (const char* name : {"frame_000000.png", "frame_000001.png", "frame_000002.png"}) {
    const cv::Mat image = vision::imread((out / name).string(), cv::IMREAD_UNCHANGED);
    EXPECT_EQ(image.cols, 736) << name;
    EXPECT_EQ(image.rows, 571) << name;
  }
  EXPECT_EQ(server.frames_rendered(), 3u);
  std::filesystem::remove_all(out);
}

// A realism profile that does not exist or holds an unknown key is bad input
// (exit 2), refused before anything binds a port.
TEST(RigSim, BadRealismProfileExitsTwo) {
  const std::string config = std::string(RIG_SOURCE_DIR) + "/config/sim.toml";
  EXPECT_EQ(run_rig({"sim", "--config", config, "--realism", "nosuchprofile"}), 2);
  const auto bad = std::filesystem::temp_directory_path() / "rig_sim_bad_profile.toml";
  std::ofstream(bad) << "[optics]\nblur = 1\n";
  EXPECT_EQ(run_rig({"sim", "--config", config, "--realism", bad.string()}), 2);
  std::filesystem::remove(bad);
}

TEST(RigCapture, MissingCameraExitsOneAndBadSpecExitsTwo) {
  const std::string out = (std::filesystem::temp_directory_path() / "rig_capture_fail").string();
  EXPECT_EQ(run_rig({"capture", "--camera", "v4l2:/dev/video97", "--frames", "1", "--out", out}),
            1);
  EXPECT_EQ(run_rig({"capture", "--camera", "usb:0", "--frames", "1", "--out", out}), 2);
  std::filesystem::remove_all(out);
}

}  // namespace
