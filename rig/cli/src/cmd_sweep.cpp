// rig sweep SWEEP.toml: the product's main job. Drives the bench
// through the sweep file's plan, measures every position with every solver
// and logs it to the run database; --resume continues a run that stopped;
// --replay measures the frames a run saved again, into a new run (rig/replay.hpp).
//
// Output: on a terminal a progress bar with ETA on stderr; otherwise one line
// per position on stdout. At the end, a summary that says where the results
// are and how to resume or report.
//
// Exit codes: 0 the run completed; 1 it was aborted or failed (the database
// holds everything measured; the summary says how to resume); 2 bad input
// (sweep file, calibration not matching the camera or the recorded frames,
// unknown run, a replay of a run without saved frames).
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "commands.hpp"
#include "db/store/store.hpp"
#include "motion/errors.hpp"
#include "motion/modbus_bench.hpp"
#include "rig/sweep/controller.hpp"
#include "rig/sweep/replay.hpp"
#include "rig/sweep/run_record.hpp"
#include "rig/sweep/sweep_config.hpp"
#include "rig/telemetry/progress_view.hpp"
#include "rig/telemetry/telemetry.hpp"
#include "vision/frame_source.hpp"

namespace rig::cli {
namespace {

struct SweepArgs {
  std::string sweep_file;
  std::string database;
  std::int64_t resume_run = 0;
  std::int64_t replay_run = 0;
  int wait_subscribers = 0;
  double wait_subscribers_s = 10;
  bool no_progress = false;
};

// SIGINT/SIGTERM: finish the current position, then end the run aborted.
std::atomic<int> g_signal{0};
extern "C" void on_stop_signal(int signal) {
  g_signal.store(signal);
}

class SignalWatch {
 public:
  explicit SignalWatch(telemetry::ControlState& control) : control_(control) {
    struct sigaction action {};
    action.sa_handler = on_stop_signal;
    sigemptyset(&action.sa_mask);
    // A system call the signal lands in (a Modbus read, a camera wait) is
    // restarted instead of failing with EINTR as a link or capture fault.
    action.sa_flags = SA_RESTART;
    sigaction(SIGINT, &action, &old_int_);
    sigaction(SIGTERM, &action, &old_term_);
    thread_ = std::thread([this] {
      while (!done_.load()) {
        if (const int s = g_signal.exchange(0)) {
          control_.request_abort(std::string(s == SIGINT ? "SIGINT" : "SIGTERM") + " received");
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    });
  }
  ~SignalWatch() {
    done_.store(true);
    thread_.join();
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }

 private:
  telemetry::ControlState& control_;
  std::atomic<bool> done_{false};
  std::thread thread_;
  struct sigaction old_int_ {
  }, old_term_{};
};

class BadInput : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One frame before anything moves: the camera answers, and its image is the
// size the calibration describes.
void check_camera(vision::FrameSource& camera, const sweep::SweepConfig& config) {
  camera.trigger();
  const vision::Frame frame = camera.grab(config.grab_timeout);
  const vision::Camera& model = config.camera;
  if (frame.image.cols != model.width_px() || frame.image.rows != model.height_px()) {
    throw BadInput(config.sweep_file +
                   ": capture.calibration: " + config.calibration_description() + " is for " +
                   std::to_string(model.width_px()) + "x" + std::to_string(model.height_px()) +
                   " px but camera " + config.camera_spec + " delivers " +
                   std::to_string(frame.image.cols) + "x" + std::to_string(frame.image.rows) +
                   " px; expected the calibration of this camera at this resolution");
  }
}

// Opens the camera and checks one frame. A GigE camera whose previous
// controller died (kill -9, power loss of the host) still holds that
// controller's stream until its heartbeat timeout expires (a few seconds), so
// a camera that refuses us or sends nothing is asked again for up to 15 s.
std::unique_ptr<vision::FrameSource> open_camera(const sweep::SweepConfig& config) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
  for (int attempt = 1;; ++attempt) {
    auto camera = vision::make_frame_source(config.camera_spec, config.capture);
    try {
      camera->open();
      check_camera(*camera, config);
      return camera;
    } catch (const vision::CaptureError& e) {
      // A camera that answers but refuses us (held by another controller)
      // or sends nothing is worth asking again; one that does not answer at
      // all is absent, and waiting would only delay the message.
      const std::string why = e.what();
      const bool held = dynamic_cast<const vision::CaptureTimeout*>(&e) != nullptr ||
                        why.find(" refused") != std::string::npos;
      if (!held || std::chrono::steady_clock::now() > deadline) throw;
      std::cerr << "rig sweep: camera attempt " << attempt << ": " << e.what()
                << "; asking again (a controller that died may hold the camera until its "
                << "heartbeat expires)\n";
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
    }
  }
}

// Telemetry and control of one sweep. Bound before anything else happens, so
// that a second sweep on the same ports stops before it touches the camera,
// the bench or the database.
class LiveLink {
 public:
  explicit LiveLink(const telemetry::TelemetryEndpoints& endpoints)
      : publisher(endpoints.publish),
        server_(endpoints.control, control, [this] { return status(); }),
        signals_(control) {}

  // While the guard lives, the control socket's `status` describes
  // `controller`; afterwards it repeats the controller's last status (the
  // guard detaches on every path out, exceptions included).
  class Attached {
   public:
    Attached(LiveLink& link, sweep::Controller& controller) : link_(link) {
      std::lock_guard<std::mutex> lock(link_.mutex_);
      link_.live_ = &controller;
    }
    ~Attached() {
      std::lock_guard<std::mutex> lock(link_.mutex_);
      link_.last_ = link_.live_->status();
      link_.live_ = nullptr;
    }
    Attached(const Attached&) = delete;
    Attached& operator=(const Attached&) = delete;

   private:
    LiveLink& link_;
  };

  void set_run(std::int64_t run_id) {
    std::lock_guard<std::mutex> lock(mutex_);
    last_ = {{"state", "starting"}, {"run_id", run_id}};
  }
  std::string control_endpoint() const { return server_.endpoint(); }

  telemetry::ControlState control;
  telemetry::TelemetryPublisher publisher;

 private:
  nlohmann::json status() {
    std::lock_guard<std::mutex> lock(mutex_);
    return live_ ? live_->status() : last_;
  }

  std::mutex mutex_;
  sweep::Controller* live_ = nullptr;
  nlohmann::json last_ = {{"state", "starting"}};
  telemetry::ControlServer server_;  // its thread calls status() until it is destroyed
  SignalWatch signals_;              // SIGINT/SIGTERM from here on: an abort request
};

// What drives a run once the run exists: the controller, progress, the
// summary. `again` is the command line that continues a run that did not
// complete.
int drive_run(const SweepArgs& args, const sweep::SweepConfig& config, const sweep::SweepPlan& plan,
              motion::Bench& bench, vision::FrameSource& camera, db::store::Store& store,
              std::int64_t run_id, LiveLink& link, const std::string& again) {
  telemetry::ControlState& control = link.control;
  telemetry::TelemetryPublisher& publisher = link.publisher;
  link.set_run(run_id);
  std::cout << "rig sweep: run " << run_id << " in " << store.path() << ", " << plan.size()
            << " positions (" << plan.description() << "), telemetry " << publisher.endpoint()
            << ", control " << link.control_endpoint() << std::endl;
  if (args.wait_subscribers > 0 &&
      !publisher.wait_for_subscribers(
          args.wait_subscribers,
          std::chrono::milliseconds(static_cast<int>(args.wait_subscribers_s * 1000)))) {
    std::cerr << "rig sweep: no telemetry subscriber on " << publisher.endpoint() << " within "
              << args.wait_subscribers_s << " s; going on without\n";
  }

  sweep::Controller controller(config, plan, bench, camera, store, run_id, control, &publisher);
  // On a terminal: a progress bar with ETA redrawn on stderr, faults and
  // pauses as lines above it; otherwise one line per message on stdout.
  const bool terminal = telemetry::is_terminal(STDERR_FILENO) && !args.no_progress;
  telemetry::ProgressPrinter progress(terminal ? std::cerr : std::cout, terminal,
                                      telemetry::terminal_width(100, STDERR_FILENO));
  controller.set_observer([&](const nlohmann::json& message) { progress.update(message); });

  sweep::RunOutcome outcome;
  {
    const LiveLink::Attached attached(link, controller);
    outcome = controller.run();
  }
  std::cout << "rig sweep: run " << run_id << " " << db::store::to_string(outcome.status)
            << (outcome.reason.empty() ? "" : ": " + outcome.reason) << "\n"
            << "  positions: " << outcome.positions_ok << " ok, " << outcome.positions_failed
            << " failed in this session; " << outcome.stored_total << " of " << plan.size()
            << " stored\n"
            << "  database:  " << store.path() << "\n";
  if (outcome.status == db::store::RunStatus::kCompleted) {
    std::cout << "  report:    rig report " << store.path() << " --run " << run_id
              << " --out <folder>\n";
    return kExitOk;
  }
  std::cout << "  " << again << "\n";
  return kExitFailure;
}

// rig sweep --replay RUN: the recorded run's plan, its saved frames, today's
// calibration, layout, geometry and solvers, into a new run of the same
// database. No bench and no camera are opened.
int run_replay(const SweepArgs& args, const sweep::SweepConfig& loaded, const std::string& database,
               LiveLink& link) {
  const std::string which = "--replay " + std::to_string(args.replay_run);
  // A replay reads an existing database; it must not create an empty one.
  if (!std::filesystem::exists(database))
    throw BadInput(which + ": database " + database +
                   " does not exist; expected the database of the run to replay (--db)");
  db::store::StoreOptions store_options;
  store_options.durable_commits = loaded.durable_commits;
  store_options.record_store_time = true;
  db::store::Store store(database, store_options);
  std::shared_ptr<const sweep::RecordedRun> recorded;
  try {
    recorded = std::make_shared<const sweep::RecordedRun>(
        sweep::RecordedRun::load(store, args.replay_run));
  } catch (const db::store::StoreError& e) {
    throw BadInput(which + ": " + e.what());
  } catch (const sweep::PlanError& e) {
    throw BadInput(which + ": the run's stored plan: " + e.what());
  }
  const sweep::SweepConfig config = replay_config(loaded, *recorded);
  const sweep::SweepPlan& plan = recorded->plan();

  const nlohmann::json replay_of = {{"database", std::filesystem::absolute(store.path()).string()},
                                    {"run", args.replay_run}};
  const std::int64_t run_id =
      store.start_run(describe_run(config, plan, {{"replay_of", replay_of}}));
  store.record_event(run_id, "start", "rig sweep --replay " + std::to_string(args.replay_run));

  auto cursor = std::make_shared<sweep::ReplayCursor>(recorded);
  sweep::ReplayBench bench(cursor);
  sweep::ReplayFrames frames(cursor);
  frames.open();
  return drive_run(args, config, plan, bench, frames, store, run_id, link,
                   "replay again: rig sweep " + config.sweep_file + " --db " + store.path() +
                       " --replay " + std::to_string(args.replay_run) +
                       " (a replay run is not resumed)");
}

int run_sweep(const SweepArgs& args) {
  if (args.replay_run > 0 && args.resume_run > 0)
    throw BadInput("--replay " + std::to_string(args.replay_run) + " and --resume " +
                   std::to_string(args.resume_run) +
                   " together: --replay measures a run's saved frames into a new run, --resume "
                   "continues a run on the bench; expected one of them");
  sweep::SweepConfig config = sweep::load_sweep_config(args.sweep_file);
  const std::string database = args.database.empty() ? config.database_path : args.database;
  LiveLink link(config.telemetry);  // validated with the sweep file
  if (args.replay_run > 0) return run_replay(args, config, database, link);

  // The camera first: a wrong calibration must stop the sweep before the bench moves.
  std::unique_ptr<vision::FrameSource> camera = open_camera(config);

  motion::ModbusBench bench(config.bench_url, config.bench_profile);
  if (config.speed_mm_s) bench.set_speed(*config.speed_mm_s);

  if (const auto parent = std::filesystem::path(database).parent_path(); !parent.empty())
    std::filesystem::create_directories(parent);
  db::store::StoreOptions store_options;
  store_options.durable_commits = config.durable_commits;
  store_options.record_store_time = true;
  db::store::Store store(database, store_options);

  // Everything is checked before anything moves or is written: a resume's
  // stored plan and files first, then the bench is homed, then the run is
  // started or resumed.
  sweep::SweepPlan plan = config.plan;
  std::optional<db::store::Run> resumed;
  if (args.resume_run > 0) {
    try {
      resumed = store.run(args.resume_run);
    } catch (const db::store::StoreError& e) {
      throw BadInput(std::string("--resume ") + std::to_string(args.resume_run) + ": " + e.what());
    }
    const nlohmann::json stored_config =
        nlohmann::json::parse(resumed->description.config_json, nullptr, false);
    if (stored_config.is_object() && stored_config.contains("replay_of"))
      throw BadInput("--resume " + std::to_string(resumed->id) + ": run " +
                     std::to_string(resumed->id) + " is a replay (of " +
                     stored_config["replay_of"].dump() +
                     "); a replay is not resumed on the bench: replay the original run again "
                     "with --replay");
    plan = plan_for_resume(*resumed, config);
  }

  // Homing is needed once per power-up of the drive; a resumed run on a homed
  // bench does not drive it home and back.
  if (config.home_first && !bench.status().homed) {
    bench.home();
    bench.wait_settled(std::chrono::milliseconds(config.bench_profile.timing.home_timeout_ms));
  }
  if (link.control.abort_requested()) {
    std::cerr << "rig sweep: " << link.control.abort_reason()
              << " before the run started; nothing was recorded\n";
    return kExitFailure;
  }

  std::int64_t run_id = 0;
  if (resumed) {
    store.resume_run(resumed->id);
    run_id = resumed->id;
    store.record_event(run_id, "resume", "rig sweep --resume");
  } else {
    run_id = store.start_run(describe_run(config, plan));
  }

  return drive_run(args, config, plan, bench, *camera, store, run_id, link,
                   "resume:    rig sweep " + config.sweep_file + " --db " + store.path() +
                       " --resume " + std::to_string(run_id));
}

}  // namespace

void add_sweep_command(CLI::App& app, ExitStatus& status) {
  auto args = std::make_shared<SweepArgs>();
  auto* cmd = app.add_subcommand(
      "sweep",
      "Drive the bench through a sweep file's plan; at every position take N frames after the "
      "bench settled, run every pose solver and log bench position against each solver's "
      "distance in the run database. Resumable; live telemetry and control over ZeroMQ "
      "(rig monitor, rig ctl).");
  cmd->add_option("SWEEP", args->sweep_file, "Sweep file (TOML), e.g. config/sweeps/ci.toml")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--db", args->database,
                  "Run database (SQLite); default: the sweep file's [database] path");
  cmd->add_option("--resume", args->resume_run,
                  "Continue run RUN of the database from its first missing position (the "
                  "sweep file and the files it names must be those the run started with; positions "
                  "stored as failed are kept, not measured again)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--replay", args->replay_run,
                  "Measure the frames run RUN saved ([capture] save_frames) again, into a new "
                  "run of the same database: the run's plan and recorded bench read-backs, this "
                  "sweep file's calibration, target layout, rig geometry and frames_per_position "
                  "(at most the run's), today's solvers. No bench or camera is used, no frames "
                  "are saved again (each frame names its PNG as source), and every position is "
                  "visited once (a position the run did not measure, or whose PNG is missing or "
                  "changed, is stored as failed). Not with --resume.")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--wait-subscribers", args->wait_subscribers,
                  "Before the first move, wait for this many telemetry subscribers (rig "
                  "monitor), so that they see the whole run")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--wait-subscribers-s", args->wait_subscribers_s,
                  "How long to wait for them, seconds (then go on without)");
  cmd->add_flag("--no-progress", args->no_progress, "Log one line per position even on a terminal");
  cmd->footer(
      "Example (with `rig sim --config config/sim.toml` running):\n"
      "  rig sweep config/sweeps/ci.toml --db out/ci/run.db\n"
      "  rig sweep config/sweeps/ci.toml --db out/ci/run.db --resume 1\n"
      "Replay run 1's saved frames (no rig needed) into a new run:\n"
      "  rig sweep config/sweeps/ci.toml --db out/ci/run.db --replay 1");
  cmd->callback([&status, args] {
    try {
      status.code = run_sweep(*args);
    } catch (const sweep::SweepConfigError& e) {
      std::cerr << "rig sweep: " << e.what() << "\n";
      status.code = kExitBadInput;
    } catch (const sweep::PlanError& e) {
      std::cerr << "rig sweep: " << e.what() << "\n";
      status.code = kExitBadInput;
    } catch (const BadInput& e) {
      std::cerr << "rig sweep: " << e.what() << "\n";
      status.code = kExitBadInput;
    } catch (const sweep::RunMismatch& e) {
      std::cerr << "rig sweep: " << e.what() << "\n";
      status.code = kExitBadInput;
    } catch (const db::store::SchemaError& e) {
      std::cerr << "rig sweep: " << e.what() << "\n";
      status.code = kExitBadInput;
    } catch (const telemetry::EndpointError& e) {
      std::cerr << "rig sweep: telemetry: " << e.what() << "\n";
      status.code = kExitBadInput;
    } catch (const telemetry::TelemetryError& e) {  // e.g. the port is taken by another sweep
      std::cerr << "rig sweep: telemetry: " << e.what() << "\n";
      status.code = kExitFailure;
    } catch (const vision::CaptureError& e) {
      std::cerr << "rig sweep: camera: " << e.what() << "\n";
      status.code = kExitFailure;
    } catch (const motion::BenchError& e) {
      std::cerr << "rig sweep: bench: " << e.what() << "\n";
      status.code = kExitFailure;
    } catch (const db::store::StoreError& e) {
      std::cerr << "rig sweep: database: " << e.what() << "\n";
      status.code = kExitFailure;
    }
  });
}

}  // namespace rig::cli
