// The subcommands of `rig`. Each lives in its own cmd_<name>.cpp, adds itself
// to the app with its options, --help text and an example, and returns the
// process exit code through the callback it installs, which runs the
// command's body through run_command (exit_codes.hpp).
#pragma once

#include <CLI/CLI.hpp>

#include "exit_codes.hpp"

namespace rig::cli {

// Set by a subcommand's callback; main() returns it.
struct ExitStatus {
  int code = kExitOk;
};

// rig solve FILE|- (cmd_solve.cpp).
void add_solve_command(CLI::App& app, ExitStatus& status);

// rig marker --id N --size-mm 50 --out FILE (cmd_marker.cpp).
void add_marker_command(CLI::App& app, ExitStatus& status);
// rig target --target FILE --out FILE (cmd_target.cpp).
void add_target_command(CLI::App& app, ExitStatus& status);

// rig capture --camera SPEC --frames N --out DIR (cmd_capture.cpp).
void add_capture_command(CLI::App& app, ExitStatus& status);

// rig bench status|home|move|jog|stop|reset (cmd_bench.cpp).
void add_bench_command(CLI::App& app, ExitStatus& status);
// rig sim bench (cmd_sim.cpp).
void add_sim_command(CLI::App& app, ExitStatus& status);

// rig detect IMAGE... [--camera FILE] [--target FILE] [--json] (cmd_detect.cpp).
void add_detect_command(CLI::App& app, ExitStatus& status);

// rig sweep SWEEP.toml [--db FILE] [--resume RUN] [--replay RUN] (cmd_sweep.cpp).
void add_sweep_command(CLI::App& app, ExitStatus& status);
// rig monitor [--endpoint E] (cmd_monitor.cpp).
void add_monitor_command(CLI::App& app, ExitStatus& status);
// rig ctl status|pause|resume|abort [--endpoint E] (cmd_ctl.cpp).
void add_ctl_command(CLI::App& app, ExitStatus& status);
// rig report DB [--run ID] [--baseline DB[:RUN]] [--fail-on-regression] --out DIR (cmd_report.cpp).
void add_report_command(CLI::App& app, ExitStatus& status);
// rig calibrate DB[:RUN] --out DIR [--fix NAME] (cmd_calibrate.cpp).
void add_calibrate_command(CLI::App& app, ExitStatus& status);

}  // namespace rig::cli
