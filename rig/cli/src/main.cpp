// rig: validates camera-to-target distance estimation on a real or simulated
// bench. `rig --help` lists the subcommands; each has --help with an example.
#include <exception>
#include <iostream>

#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"rig: camera pose solvers measured against a robot bench (Maidi et al. 2010)"};
  app.set_version_flag("--version", std::string("rig ") + RIG_VERSION);
  app.require_subcommand(1);
  rig::cli::ExitStatus status;
  rig::cli::add_solve_command(app, status);
  rig::cli::add_capture_command(app, status);
  rig::cli::add_marker_command(app, status);
  rig::cli::add_detect_command(app, status);
  rig::cli::add_target_command(app, status);
  rig::cli::add_bench_command(app, status);
  rig::cli::add_sim_command(app, status);
  rig::cli::add_sweep_command(app, status);
  rig::cli::add_monitor_command(app, status);
  rig::cli::add_ctl_command(app, status);
  rig::cli::add_report_command(app, status);
  rig::cli::add_calibrate_command(app, status);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : rig::cli::kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "rig: " << e.what() << "\n";
    return rig::cli::kExitFailure;
  }
  return status.code;
}
