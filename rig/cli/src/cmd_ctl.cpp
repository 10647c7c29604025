// rig ctl: status, pause, resume or abort a running sweep over its control socket.
#include <chrono>
#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "rig/telemetry/progress_view.hpp"
#include "rig/telemetry/telemetry.hpp"

namespace rig::cli {
namespace {

struct CtlArgs {
  std::string command;
  std::string endpoint = telemetry::TelemetryEndpoints().control;
  std::string reason;
  int timeout_ms = 2000;
  bool json = false;
};

// What the reply means for a person: the status as one line
// (telemetry::describe_status), otherwise a short line with the state the
// sweep reports.
void print_reply(const CtlArgs& a, const nlohmann::json& reply) {
  const nlohmann::json& status = reply.contains("status") ? reply["status"] : nlohmann::json();
  if (a.command == "status") {
    std::cout << telemetry::describe_status(status) << "\n";
    return;
  }
  const std::string state =
      status.is_object() && status.contains("state") && status["state"].is_string()
          ? status["state"].get<std::string>()
          : "unknown";
  if (a.command == "pause")
    std::cout << "pause requested (the sweep stops after the current position); state " << state
              << "\n";
  else if (a.command == "resume")
    std::cout << "resume requested; state " << state << "\n";
  else
    std::cout << "abort requested (the sweep stops after the current position"
              << (a.reason.empty() ? "" : "; reason: " + a.reason) << "); state " << state << "\n";
}

int run_ctl(const CtlArgs& a) {
  telemetry::validate_endpoint(a.endpoint, /*allow_remote=*/true, "--endpoint");
  const nlohmann::json reply = telemetry::send_control(
      a.endpoint, a.command, std::chrono::milliseconds(a.timeout_ms), a.reason);
  if (a.json) std::cout << reply.dump() << "\n";
  if (!reply.value("ok", false)) {
    std::cerr << "rig ctl: the sweep refused \"" << a.command
              << "\": " << reply.value("error", std::string("no reason given")) << "\n";
    return kExitFailure;
  }
  if (!a.json) print_reply(a, reply);
  return kExitOk;
}

}  // namespace

void add_ctl_command(CLI::App& app, ExitStatus& status) {
  auto args = std::make_shared<CtlArgs>();
  CLI::App* cmd =
      app.add_subcommand("ctl", "Ask a running sweep for its status, or pause, resume or abort it");
  cmd->add_option("COMMAND", args->command,
                  "status: print the sweep's state, progress and ETA (one line; JSON with --json)\n"
                  "pause: stop after the current position until resumed\n"
                  "resume: continue a paused sweep (also one the controller paused after a "
                  "bench alarm)\n"
                  "abort: stop after the current position and end the run as aborted")
      ->required()
      ->check(CLI::IsMember({"status", "pause", "resume", "abort"}));
  cmd->add_option("--endpoint", args->endpoint, "The sweep's control (REP) endpoint")
      ->capture_default_str();
  cmd->add_option("--reason", args->reason,
                  "Why (abort only): stored with the run and shown by rig monitor");
  cmd->add_option("--timeout-ms", args->timeout_ms,
                  "How long to wait for the reply, ms; a sweep answers between its steps within "
                  "milliseconds, so a timeout means no sweep is running there")
      ->capture_default_str()
      ->check(CLI::Range(1, 600000));
  cmd->add_flag("--json", args->json, "Print the reply as one line of JSON (for scripts)");
  cmd->footer(
      "Exit status: 0 the sweep accepted the command, 1 no sweep answered or it refused, "
      "2 bad input.\n"
      "Example: rig ctl pause\n"
      "         rig ctl abort --reason \"lens cap on\" --endpoint tcp://127.0.0.1:5557");
  cmd->callback(
      [&status, args] { status.code = run_command("ctl", [&] { return run_ctl(*args); }); });
}

}  // namespace rig::cli
