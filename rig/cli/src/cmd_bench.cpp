// rig bench: status, homing, moves, jogging and stopping of a bench, for a
// person at a real rig (or the simulated one).
#include <chrono>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "commands.hpp"
#include "motion/bench_url.hpp"
#include "motion/drive_profile.hpp"
#include "motion/driven_bench.hpp"

namespace rig::cli {
namespace {

struct BenchArgs {
  std::string url;
  std::string profile;
  std::optional<double> speed_mm_s;  // none: the profile's default
  double x_mm = 0, y_mm = 0;
};

void print(const motion::BenchStatus& s) {
  std::cout << std::fixed << std::setprecision(4) << "position x " << s.position.x_mm << " mm, y "
            << s.position.y_mm << " mm\n"
            << "homed " << s.homed << ", moving " << s.moving << ", in position " << s.in_position
            << ", emergency stop " << s.emergency_stop << "\n"
            << "alarm " << s.alarm << " code " << s.alarm_code
            << (s.alarm_code ? " (" + s.alarm_meaning + ")" : std::string()) << "\n";
}

// Connects, runs `action` and prints the bench's status; errors give the
// exit code (run_command): bad input (profile, URL, soft limits) 2, anything
// the bench did 1.
template <class Action>
int with_bench(const BenchArgs& a, Action action) {
  return run_command("bench", [&] {
    const std::unique_ptr<motion::DrivenBench> bench =
        motion::open_bench(motion::BenchUrl::parse(a.url), motion::load_drive_profile(a.profile));
    if (a.speed_mm_s) bench->set_speed(*a.speed_mm_s);  // refuses 0, negative, NaN (exit 2)
    action(*bench);
    print(bench->status());
    return kExitOk;
  });
}

std::chrono::milliseconds settle_timeout(const motion::DrivenBench& b) {
  return std::chrono::milliseconds(b.profile().timing.settle_timeout_ms);
}

CLI::App* add_action(CLI::App* parent, const std::string& name, const std::string& help,
                     const std::string& example, const std::shared_ptr<BenchArgs>& args) {
  CLI::App* cmd = parent->add_subcommand(name, help);
  cmd->add_option("--bench", args->url,
                  "modbus-tcp://HOST:PORT or modbus-rtu:///dev/ttyUSB0?baud=115200&parity=N&unit=1")
      ->required();
  cmd->add_option("--profile", args->profile, "Drive profile (TOML), e.g. config/benches/sim.toml")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->footer("Example: rig bench " + example);
  return cmd;
}

}  // namespace

void add_bench_command(CLI::App& app, ExitStatus& status) {
  CLI::App* bench =
      app.add_subcommand("bench", "Status, home, move, jog, stop and reset the alarm of a bench");
  bench->require_subcommand(1);
  bench->footer(
      "Example: rig bench status --bench modbus-tcp://127.0.0.1:1502 "
      "--profile config/benches/sim.toml");
  auto args = std::make_shared<BenchArgs>();
  const std::string where = "--bench modbus-tcp://127.0.0.1:1502 --profile config/benches/sim.toml";

  add_action(bench, "status", "Print position and status bits", "status " + where, args)
      ->callback([&status, args] { status.code = with_bench(*args, [](auto&) {}); });

  add_action(bench, "home", "Home the bench and wait until it is homed and still", "home " + where,
             args)
      ->callback([&status, args] {
        status.code = with_bench(*args, [](motion::DrivenBench& b) {
          b.home();
          b.wait_settled(std::chrono::milliseconds(b.profile().timing.home_timeout_ms));
        });
      });

  CLI::App* move = add_action(bench, "move", "Move to X Y (mm, absolute) and wait until settled",
                              "move 120.5 40 " + where, args);
  move->add_option("X", args->x_mm, "Target X, mm")->required();
  move->add_option("Y", args->y_mm, "Target Y, mm")->required();
  move->add_option("--speed", args->speed_mm_s, "mm/s (default: the profile's)");
  move->callback([&status, args] {
    status.code = with_bench(*args, [&](motion::DrivenBench& b) {
      b.move_to(args->x_mm, args->y_mm);
      b.wait_settled(settle_timeout(b));
    });
  });

  CLI::App* jog = add_action(bench, "jog", "Move by DX DY (mm, relative) and wait until settled",
                             "jog 0.1 0 " + where + "\n         rig bench jog " + where +
                                 " -- -0.1 0   (negative steps after --)",
                             args);
  jog->add_option("DX", args->x_mm, "Step along X, mm")->required();
  jog->add_option("DY", args->y_mm, "Step along Y, mm")->required();
  jog->add_option("--speed", args->speed_mm_s, "mm/s (default: the profile's)");
  jog->callback([&status, args] {
    status.code = with_bench(*args, [&](motion::DrivenBench& b) {
      const motion::XY p = b.position();
      b.move_to(p.x_mm + args->x_mm, p.y_mm + args->y_mm);
      b.wait_settled(settle_timeout(b));
    });
  });

  add_action(bench, "reset", "Clear a drive alarm (after fixing its cause)", "reset " + where, args)
      ->callback([&status, args] {
        status.code = with_bench(*args, [](motion::DrivenBench& b) { b.reset_alarm(); });
      });

  add_action(bench, "stop", "Stop the bench (decelerate) and wait until it stands still",
             "stop " + where, args)
      ->callback([&status, args] {
        status.code = with_bench(*args, [](motion::DrivenBench& b) {
          b.stop();
          b.wait_settled(settle_timeout(b));
        });
      });
}

}  // namespace rig::cli
