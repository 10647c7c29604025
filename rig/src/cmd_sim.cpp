// rig sim: the simulated rig on loopback. `rig sim bench` runs the simulated
// Modbus bench alone. The simulated camera is another part started beside the
// bench in SimRig (see start_parts), so `rig sim` can run the whole rig.
#include <csignal>
#include <iostream>
#include <memory>
#include <motion/drive_profile.hpp>
#include <motion/errors.hpp>
#include <sim/bench_config.hpp>
#include <sim/bench_server.hpp>
#include <string>

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

int run_until_stopped(const SimBenchOptions& bench_options) {
  StopSignals signals;  // before any server thread exists
  SimRig rig;
  try {
    rig.bench = start_bench(bench_options);
  } catch (const motion::ProfileError& e) {
    std::cerr << "rig sim: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "rig sim: " << e.what() << "\n";
    return kExitFailure;
  }
  const int sig = signals.wait();
  std::cout << "rig sim: " << (sig == SIGINT ? "SIGINT" : "SIGTERM") << ", stopping" << std::endl;
  rig.bench->stop();
  return kExitOk;
}

}  // namespace

void add_sim_command(CLI::App& app, ExitStatus& status) {
  CLI::App* sim = app.add_subcommand("sim", "Run the simulated rig (Modbus bench) on loopback");
  sim->require_subcommand(1);
  sim->footer("Example: rig sim bench --port 1502 --config config/benches/sim.toml");

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
