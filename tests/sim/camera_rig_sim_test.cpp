// `rig sim --config FILE` as a process: it prints the bench URL and the
// camera's id and address, serves frames over GigE Vision, and stops cleanly
// on SIGTERM.
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "vision/gige_source.hpp"

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
  const std::string rig = std::string(RIG_BINARY_DIR) + "/rig/rig";
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
  char* argv[] = {const_cast<char*>(rig.c_str()), const_cast<char*>("sim"),
                  const_cast<char*>("--config"), config_path.data(), nullptr};
  pid_t pid = -1;
  ASSERT_EQ(posix_spawn(&pid, rig.c_str(), &actions, nullptr, argv, environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  close(out[1]);

  std::string text;
  const bool up = read_until(out[0], text, "Aravis-Fake-RIGSIMTEST at 127.0.0.1", 10s);
  EXPECT_TRUE(up) << text;
  EXPECT_NE(text.find("modbus-tcp://127.0.0.1:"), std::string::npos) << text;
  if (up) {
    vision::GigeSource camera("127.0.0.1");
    camera.open();
    camera.trigger();
    EXPECT_EQ(camera.grab(3000ms).image.cols, 736);
  }
  kill(pid, SIGTERM);
  EXPECT_TRUE(read_until(out[0], text, "SIGTERM, stopping", 5s)) << text;
  int status = 0;
  waitpid(pid, &status, 0);
  close(out[0]);
  std::filesystem::remove(config);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
}

}  // namespace
