// rig-sim (run as `rig sim`): the simulated rig on loopback. `rig sim bench`
// runs the simulated Modbus bench alone; `rig sim --config config/sim.toml`
// runs the bench and, beside it in SimRig, the GigE camera whose frames are
// rendered from the bench's actual position (sim/camera/server.hpp).
#include <CLI/CLI.hpp>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "config/error.hpp"
#include "motion/drive_profile.hpp"
#include "sim/bench/config.hpp"
#include "sim/bench/server.hpp"
#include "sim/camera/config.hpp"
#include "vision/camera.hpp"

namespace {

// Exit codes, as every rig program: 0 success, 1 a failure while running, 2 bad input.
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitBadInput = 2;

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
  // The rig's realism profile, whose [bench.x] / [bench.y] replace the file's
  // imperfections; null for `rig sim bench`.
  const sim::camera::RealismProfile* realism = nullptr;
};

// The parts of the simulated rig that run together. A part is started by
// start_parts and stopped, in reverse order, when SimRig is destroyed.
struct SimRig {
  std::unique_ptr<sim::bench::BenchServer> bench;
  std::unique_ptr<sim::camera::CameraServer> camera;  // renders from bench->actual_position_mm()
};

std::unique_ptr<sim::bench::BenchServer> start_bench(const SimBenchOptions& o) {
  motion::DriveProfile profile = motion::load_drive_profile(o.config);
  sim::bench::BenchSimConfig config = sim::bench::load_bench_sim_config(o.config);
  if (o.time_scale > 0) config.time_scale = o.time_scale;
  if (o.realism != nullptr) sim::camera::apply_bench_realism(*o.realism, &config);
  sim::bench::BenchServerOptions server;
  server.host = o.host;
  server.port = o.port;
  auto bench = std::make_unique<sim::bench::BenchServer>(std::move(profile), config, server);
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
  } catch (const config::ConfigError& e) {  // any of the TOML files
    return fail(e, kExitBadInput);
  } catch (const vision::CalibrationError& e) {
    return fail(e, kExitBadInput);
  } catch (const std::exception& e) {
    return fail(e, kExitFailure);
  }
}

// The default file names are relative to the repository's top folder: said
// plainly when the file is not there (rig sim run from another folder).
// Returns kExitBadInput after printing, or nullopt when the file exists.
std::optional<int> missing_config(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(path, ec)) return std::nullopt;
  std::cerr << "rig sim: " << what << " " << path << " not found (looked for "
            << std::filesystem::absolute(path, ec).string()
            << "). Run rig sim from the repository's top folder, or name the file with --config "
               "FILE"
            << std::endl;
  return kExitBadInput;
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
  if (auto code = missing_config(bench_options.config, "the bench file")) return *code;
  StopSignals signals;  // before any server thread exists
  SimRig rig;
  if (auto code = start_or_exit_code([&] { rig.bench = start_bench(bench_options); })) return *code;
  return serve_until_signalled(signals, rig);
}

struct SimRigOptions {
  std::string config = "config/sim.toml";
  std::string realism;      // NAME or FILE; empty: the file's [realism] profile
  std::string write_truth;  // JSON file for the hidden truth; empty: none
};

void write_truth(const sim::camera::SimRigConfig& config, const std::string& path) {
  std::ofstream out(path, std::ios::trunc);
  out << sim::camera::truth_json(sim::camera::sim_truth(config), config.realism);
  out.close();
  if (!out) throw std::runtime_error("--write-truth " + path + ": cannot write the file");
  std::cout << "rig sim: truth of realism profile '" << config.realism.name << "' written to "
            << path << std::endl;
}

// rig sim --config FILE: the bench and the camera that sees from it.
int run_rig_until_stopped(const SimRigOptions& options) {
  if (auto code = missing_config(options.config, "the simulated rig file")) return *code;
  StopSignals signals;  // before any server thread exists
  SimRig rig;
  const auto code = start_or_exit_code([&] {
    sim::camera::SimRigConfig config = sim::camera::load_sim_rig_config(options.config);
    if (!options.realism.empty())
      sim::camera::override_realism(&config, options.config, options.realism);
    if (!options.write_truth.empty()) write_truth(config, options.write_truth);
    SimBenchOptions bench_options;
    bench_options.config = config.bench_config;
    bench_options.host = config.bench_host;
    bench_options.port = config.bench_port;
    bench_options.realism = &config.realism;
    rig.bench = start_bench(bench_options);
    const sim::bench::BenchServer* bench = rig.bench.get();
    rig.camera = sim::camera::make_camera_server(config, [bench] {
      const motion::XY p = bench->actual_position_mm();
      return std::make_pair(p.x_mm, p.y_mm);
    });
    rig.camera->start();
    std::cout << "rig sim camera: serving " << rig.camera->device_id() << " at "
              << rig.camera->address() << " (rig capture --camera gige:" << rig.camera->address()
              << "), realism profile '" << config.realism.name << "'" << std::endl;
  });
  if (code) return *code;
  return serve_until_signalled(signals, rig);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rig sim: the simulated rig (Modbus bench and GigE camera) on loopback"};
  app.name("rig sim");
  CLI::App* cmd = &app;
  int status = kExitOk;
  cmd->require_subcommand(0, 1);
  auto rig_options = std::make_shared<SimRigOptions>();
  cmd->add_option("--config", rig_options->config,
                  "Simulated rig file: bench, camera, target and geometry (config/sim.toml)")
      ->capture_default_str()
      ->check(CLI::ExistingFile);
  cmd->add_option("--realism", rig_options->realism,
                  "Realism profile: a NAME (realism/NAME.toml beside the rig file: ideal, lab, "
                  "paper) or a FILE; overrides the rig file's [realism] profile");
  cmd->add_option("--write-truth", rig_options->write_truth,
                  "Write the hidden truth (true camera, lens, rig geometry, print scale) as JSON "
                  "to this file before serving");
  cmd->footer(
      "Without a subcommand: the bench and the GigE camera together, until SIGINT or SIGTERM.\n"
      "Example: rig sim --config config/sim.toml\n"
      "         rig sim --config config/sim.toml --realism paper --write-truth truth.json\n"
      "         rig sim bench --port 1502 --config config/benches/sim.toml");
  cmd->callback([&status, cmd, rig_options] {
    if (cmd->get_subcommands().empty()) status = run_rig_until_stopped(*rig_options);
  });

  auto bench_options = std::make_shared<SimBenchOptions>();
  CLI::App* bench = cmd->add_subcommand(
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
  bench->callback([&status, bench_options] { status = run_until_stopped(*bench_options); });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitBadInput;
  }
  return status;
}
