// The subcommands of `rig`. Each lives in its own cmd_<name>.cpp, adds itself
// to the app with its options, --help text and an example, and returns the
// process exit code through the callback it installs.
//
// Exit codes shared by every subcommand: 0 success, 1 a failure while running
// (hardware, I/O), 2 bad input (the message names the input and what was expected).
#pragma once

#include <CLI/CLI.hpp>

namespace rig {

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitBadInput = 2;

// Set by a subcommand's callback; main() returns it.
struct ExitStatus {
  int code = kExitOk;
};

// rig marker --id N --size-mm 50 --out FILE (cmd_marker.cpp).
// rig solve FILE|- (cmd_solve.cpp).
void add_solve_command(CLI::App& app, ExitStatus& status);

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

}  // namespace rig
