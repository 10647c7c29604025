#include "rig_command.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace rig_test {

RigRun run_rig(const std::string& args, const std::string& stdin_text) {
  namespace fs = std::filesystem;
  static std::atomic<int> counter{0};
  const std::string tag = std::to_string(::getpid()) + "_" + std::to_string(counter++);
  const fs::path input = fs::temp_directory_path() / ("rig_test_stdin_" + tag);
  const fs::path errors = fs::temp_directory_path() / ("rig_test_stderr_" + tag);
  std::ofstream(input) << stdin_text;
  const std::string command = std::string(RIG_BINARY_DIR) + "/bin/rig " + args + " < " +
                              input.string() + " 2> " + errors.string();
  RigRun r;
  if (FILE* pipe = ::popen(command.c_str(), "r")) {
    std::array<char, 4096> buf;
    for (size_t n; (n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0;)
      r.out.append(buf.data(), n);
    const int status = ::pclose(pipe);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  std::ifstream err(errors);
  r.err.assign(std::istreambuf_iterator<char>(err), {});
  fs::remove(input);
  fs::remove(errors);
  return r;
}

}  // namespace rig_test
