// rig sim: the simulated rig on loopback. `rig sim bench` runs the simulated
// Modbus bench alone; `rig sim --config config/sim.toml` runs the bench and,
// beside it in SimRig, the GigE camera whose frames are rendered from the
// bench's actual position (sim/camera_server.hpp).
#include <csignal>
#include <iostream>
#include <memory>
#include <motion/drive_profile.hpp>
#include <motion/errors.hpp>
#include <optional>
#include <sim/bench_config.hpp>
#include <sim/bench_server.hpp>
#include <sim/camera_config.hpp>
#include <string>
#include <vision/camera.hpp>
#include <vision/rig_geometry.hpp>
#include <vision/target.hpp>

#include "commands.hpp"

namespace rig {
namespace {

// SIGINT and SIGTERM blocked in the calling thread, and so in every thread it
// starts afterwards, then collected synchronously by wait(): the servers stop
// from the main thread, never from a signal handler.
class StopSignals {
 public:
  StopSignals() {
    sigemptyset(&set_);
    sigaddset(&set_, SIGINT);
    sigaddset(&set_, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set_, &old_);
  }
  ~StopSignals() { pthread_sigmask(SIG_SETMASK, &old_, nullptr); }
  int wait() {
    int sig = 0;
    sigwait(&set_, &sig);
    return sig;
  }

 private:
  sigset_t set_, old_;
};

struct SimBenchOptions {
  std::string config = "config/benches/sim.toml";
  std::string host = "127.0.0.1";
  int port = 1502;
  double time_scale = 0;  // 0: the file's [sim] time_scale
};

// The parts of the simulated rig that run together. A part is started by
// start_parts and stopped, in reverse order, when SimRig is destroyed.
struct SimRig {
  std::unique_ptr<sim::BenchServer> bench;
  std::unique_ptr<sim::CameraServer> camera;  // renders from bench->actual_position_mm()
};

std::unique_ptr<sim::BenchServer> start_bench(const SimBenchOptions& o) {
  motion::DriveProfile profile = motion::load_drive_profile(o.config);
  sim::BenchSimConfig config = sim::load_bench_sim_config(o.config);
  if (o.time_scale > 0) config.time_scale = o.time_scale;
  sim::BenchServerOptions server;
  server.host = o.host;
  server.port = o.port;
  auto bench = std::make_unique<sim::BenchServer>(std::move(profile), config, server);
  bench->start();
  std::cout << "rig sim bench: serving " << bench->url() << " (map " << o.config << ", time scale "
            << config.time_scale << ")" << std::endl;
  return bench;
}

// Runs `start`; returns nullopt once the simulated rig is up, else the exit
// code: 2 for a bad configuration file, key or value, 1 for anything else.
template <typename Start>
std::optional<int> start_or_exit_code(Start&& start) {
  auto fail = [](const std::exception& e, int code) {
    std::cerr << "rig sim: " << e.what() << "\n";
    return std::optional<int>(code);
  };
  try {
    start();
    return std::nullopt;
  } catch (const motion::ProfileError& e) {
    return fail(e, kExitBadInput);
  } catch (const vision::RigConfigError& e) {
    return fail(e, kExitBadInput);
  } catch (const vision::TargetError& e) {
    return fail(e, kExitBadInput);
  } catch (const vision::CalibrationError& e) {
    return fail(e, kExitBadInput);
  } catch (const std::exception& e) {
    return fail(e, kExitFailure);
  }
}

// Serves until SIGINT or SIGTERM, then stops the camera (if any) and the bench.
int serve_until_signalled(StopSignals& signals, SimRig& rig) {
  const int sig = signals.wait();
  std::cout << "rig sim: " << (sig == SIGINT ? "SIGINT" : "SIGTERM") << ", stopping" << std::endl;
  if (rig.camera) rig.camera->stop();
  rig.bench->stop();
  return kExitOk;
}

int run_until_stopped(const SimBenchOptions& bench_options) {
  StopSignals signals;  // before any server thread exists
  SimRig rig;
  if (auto code = start_or_exit_code([&] { rig.bench = start_bench(bench_options); })) return *code;
  return serve_until_signalled(signals, rig);
}

// rig sim --config FILE: the bench and the camera that sees from it.
int run_rig_until_stopped(const std::string& config_path) {
  StopSignals signals;  // before any server thread exists
  SimRig rig;
  const auto code = start_or_exit_code([&] {
    const sim::SimRigConfig config = sim::load_sim_rig_config(config_path);
    SimBenchOptions bench_options;
    bench_options.config = config.bench_config;
    bench_options.host = config.bench_host;
    bench_options.port = config.bench_port;
    rig.bench = start_bench(bench_options);
    const sim::BenchServer* bench = rig.bench.get();
    rig.camera = sim::make_camera_server(config, [bench] {
      const motion::XY p = bench->actual_position_mm();
      return std::make_pair(p.x_mm, p.y_mm);
    });
    rig.camera->start();
    std::cout << "rig sim camera: serving " << rig.camera->device_id() << " at "
              << rig.camera->address() << " (rig capture --camera gige:" << rig.camera->address()
              << ")" << std::endl;
  });
  if (code) return *code;
  return serve_until_signalled(signals, rig);
}

}  // namespace

void add_sim_command(CLI::App& app, ExitStatus& status) {
  CLI::App* sim = app.add_subcommand("sim", "Run the simulated rig (Modbus bench) on loopback");
  sim->require_subcommand(0, 1);
  auto rig_config = std::make_shared<std::string>("config/sim.toml");
  sim->add_option("--config", *rig_config,
                  "Simulated rig file: bench, camera, target and geometry (config/sim.toml)")
      ->capture_default_str()
      ->check(CLI::ExistingFile);
  sim->footer(
      "Without a subcommand: the bench and the GigE camera together, until SIGINT or SIGTERM.\n"
      "Example: rig sim --config config/sim.toml\n"
      "         rig sim bench --port 1502 --config config/benches/sim.toml");
  sim->callback([&status, sim, rig_config] {
    if (sim->get_subcommands().empty()) status.code = run_rig_until_stopped(*rig_config);
  });

  auto bench_options = std::make_shared<SimBenchOptions>();
  CLI::App* bench = sim->add_subcommand(
      "bench", "Run the simulated XY bench alone: a Modbus TCP server with motion dynamics");
  bench
      ->add_option("--config", bench_options->config,
                   "Bench file: the drive profile (register map) it serves and its [sim] table")
      ->capture_default_str()
      ->check(CLI::ExistingFile);
  bench->add_option("--port", bench_options->port, "TCP port; 0 picks a free one (printed)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  bench->add_option("--host", bench_options->host, "Address to listen on")->capture_default_str();
  bench
      ->add_option("--time-scale", bench_options->time_scale,
                   "Simulated seconds per wall second (overrides [sim] time_scale)")
      ->check(CLI::PositiveNumber);
  bench->footer(
      "Stops cleanly on SIGINT or SIGTERM.\n"
      "Example: rig sim bench --port 1502 --config config/benches/sim.toml\n"
      "         mbpoll -m tcp -p 1502 -a 1 -0 -r 0 -t 3:int -B -c 2 -1 127.0.0.1");
  bench->callback([&status, bench_options] { status.code = run_until_stopped(*bench_options); });
}

}  // namespace rig
