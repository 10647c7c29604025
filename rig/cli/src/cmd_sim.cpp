// rig sim: runs the simulated rig, the program rig-sim that is installed beside
// rig, with the arguments that follow `sim` (`rig sim --help` is rig-sim's
// help). rig's own code never links the simulator (docs/architecture.md).
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "commands.hpp"

namespace rig::cli {
namespace {

// The folder of the running program, from /proc/self/exe.
std::filesystem::path own_folder() {
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path() : self.parent_path();
}

// Replaces this process with rig-sim ARGS; returns only on failure.
int exec_rig_sim(const std::vector<std::string>& args) {
  const std::filesystem::path program = own_folder() / "rig-sim";
  std::vector<char*> argv;
  std::string name = program.string();
  argv.push_back(name.data());
  std::vector<std::string> copies(args);
  for (auto& a : copies)
    argv.push_back(a.data());
  argv.push_back(nullptr);
  execv(name.c_str(), argv.data());
  std::cerr << "rig sim: cannot run " << name << ": " << std::strerror(errno)
            << " (rig-sim is built and installed beside rig)\n";
  return kExitFailure;
}

}  // namespace

void add_sim_command(CLI::App& app, ExitStatus& status) {
  CLI::App* sim = app.add_subcommand(
      "sim",
      "Run the simulated rig (Modbus bench and GigE camera) on loopback; see rig sim --help");
  sim->prefix_command();
  sim->set_help_flag();  // --help goes to rig-sim
  sim->footer("Example: rig sim --config config/sim.toml\n         rig sim bench --port 1502");
  sim->callback([&status, sim] {
    status.code = run_command("sim", [&] { return exec_rig_sim(sim->remaining()); });
  });
}

}  // namespace rig::cli
