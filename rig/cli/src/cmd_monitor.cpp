// rig monitor: a live view of a running sweep from its telemetry.
#include <algorithm>
#include <chrono>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "rig/telemetry/progress_view.hpp"
#include "rig/telemetry/telemetry.hpp"

namespace rig::cli {
namespace {

struct MonitorArgs {
  std::string endpoint = telemetry::TelemetryEndpoints().publish;
  bool until_stop = false;
  double timeout_s = 0;  // 0: wait for ever
  bool json = false;
  bool plain = false;
};

// Redraws the dashboard in place: cursor home, each line erased to its end
// (ANSI EL), everything below erased (ED) - no full clear, so no flicker.
void redraw(const telemetry::ProgressView& view) {
  std::string screen = view.dashboard(telemetry::terminal_width(), telemetry::terminal_height());
  std::string out = "\x1b[H";
  for (char c : screen) {
    if (c == '\n') out += "\x1b[K";
    out += c;
  }
  std::cout << out << "\x1b[J" << std::flush;
}

std::string seconds_text(double s) {
  std::ostringstream t;
  t << s;
  return t.str();
}

// Shows one message as the output mode wants it.
void show(const MonitorArgs& a, bool live, const telemetry::ProgressView& view,
          const nlohmann::json& message) {
  if (a.json)
    std::cout << message.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << "\n"
              << std::flush;
  else if (live)
    redraw(view);
  else
    std::cout << view.describe(message) << "\n" << std::flush;
}

int run_monitor(const MonitorArgs& a) {
  using Clock = std::chrono::steady_clock;
  telemetry::validate_endpoint(a.endpoint, /*allow_remote=*/true, "--endpoint");
  telemetry::TelemetrySubscriber subscriber(a.endpoint);
  const bool live = !a.json && !a.plain && telemetry::stdout_is_terminal();
  telemetry::ProgressView view;
  if (live) {
    std::cout << "\x1b[2J";
    redraw(view);
  }
  const auto silence_limit =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a.timeout_s));
  auto last_message = Clock::now();
  for (;;) {
    // Wake at least once a second so a live view follows terminal resizes.
    auto wait = std::chrono::milliseconds(1000);
    if (a.timeout_s > 0) {
      const auto left =
          std::chrono::ceil<std::chrono::milliseconds>(last_message + silence_limit - Clock::now());
      if (left.count() <= 0) {
        if (live) std::cout << "\n";
        std::cerr << "rig monitor: no telemetry from " << a.endpoint << " within "
                  << seconds_text(a.timeout_s) << " s (is a sweep running and publishing there?)\n";
        return kExitFailure;
      }
      wait = std::min(wait, left);
    }
    std::optional<nlohmann::json> message;
    try {
      message = subscriber.receive(wait);
    } catch (const telemetry::TelemetryError& e) {
      std::cerr << "rig monitor: " << e.what() << "\n";  // one bad message; keep listening
      last_message = Clock::now();
      continue;
    }
    if (!message) {
      if (live) redraw(view);
      continue;
    }
    last_message = Clock::now();
    view.update(*message);
    show(a, live, view, *message);
    if (a.until_stop && message->value("type", std::string()) == "run_stop")
      return message->value("status", std::string()) == "completed" ? kExitOk : kExitFailure;
  }
}

}  // namespace

void add_monitor_command(CLI::App& app, ExitStatus& status) {
  auto args = std::make_shared<MonitorArgs>();
  CLI::App* cmd = app.add_subcommand(
      "monitor", "Live view of a running sweep: progress, ETA, latest error per solver, faults");
  cmd->add_option("--endpoint", args->endpoint, "The sweep's telemetry (PUB) endpoint")
      ->capture_default_str();
  cmd->add_flag("--until-stop", args->until_stop,
                "Exit when the run stops: 0 if it completed, 1 if it was aborted or failed");
  cmd->add_option("--timeout-s", args->timeout_s,
                  "Exit 1 if no message arrives for this many seconds (default: wait for ever). "
                  "A sweep publishes after every position, so a few times the slowest position "
                  "is enough")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--json", args->json, "Print every message as one line of JSON, as received");
  cmd->add_flag("--plain", args->plain,
                "One plain line per message even on a terminal (the default when output is not "
                "a terminal)");
  cmd->footer(
      "A monitor that starts mid-run shows progress from the next position on; it cannot see "
      "messages sent before it subscribed.\n"
      "Exit status: 0 after a completed run (--until-stop), 1 aborted or failed run, timeout or "
      "socket error, 2 bad input.\n"
      "Example: rig monitor\n"
      "         rig monitor --until-stop --timeout-s 60 --json > run.jsonl");
  cmd->callback([&status, args] {
    status.code = run_command("monitor", [&] { return run_monitor(*args); });
  });
}

}  // namespace rig::cli
