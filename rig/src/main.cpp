// rig: validates camera-to-target distance estimation on a real or simulated
// bench. `rig --help` lists the subcommands; each has --help with an example.
#include <exception>
#include <iostream>

#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"rig: camera pose solvers measured against a robot bench (Maidi et al. 2010)"};
  app.set_version_flag("--version", std::string("rig ") + RIG_VERSION);
  app.require_subcommand(1);
  rig::ExitStatus status;
  rig::add_solve_command(app, status);
  rig::add_capture_command(app, status);
  rig::add_marker_command(app, status);
  rig::add_detect_command(app, status);
  rig::add_target_command(app, status);
  rig::add_bench_command(app, status);
  rig::add_sim_command(app, status);
  rig::add_sweep_command(app, status);
  rig::add_monitor_command(app, status);
  rig::add_ctl_command(app, status);
  rig::add_report_command(app, status);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : rig::kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "rig: " << e.what() << "\n";
    return rig::kExitFailure;
  }
  return status.code;
}
