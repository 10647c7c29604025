// rig sweep SWEEP.toml: the product's main job. Drives the bench
// through the sweep file's plan, measures every position with every solver
// and logs it to the run database; --resume continues a run that stopped;
// --replay measures the frames a run saved again, into a new run
// (rig/sweep/replay.hpp). Starting the run is rig/sweep/run_start.hpp's; this
// file turns the options into those calls, prints, and returns the exit code.
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

#include <chrono>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "commands.hpp"
#include "db/store/store.hpp"
#include "motion/driven_bench.hpp"
#include "rig/sweep/controller.hpp"
#include "rig/sweep/run_start.hpp"
#include "rig/sweep/sweep_camera.hpp"
#include "rig/sweep/sweep_config.hpp"
#include "rig/telemetry/progress_view.hpp"
#include "rig/telemetry/telemetry.hpp"
#include "sweep_link.hpp"
#include "vision/frame_source.hpp"

namespace rig::cli {
namespace {

struct SweepArgs {
  std::string sweep_file;
  std::string database;
  std::int64_t resume_run = 0;
  std::int64_t replay_run = 0;
  bool retry_failed = false;
  int wait_subscribers = 0;
  double wait_subscribers_s = 10;
  bool no_progress = false;
};

// Waits for the subscribers --wait-subscribers asks for; says so when they
// do not come.
void wait_for_subscribers(const SweepArgs& args, telemetry::TelemetryPublisher& publisher) {
  if (args.wait_subscribers > 0 &&
      !publisher.wait_for_subscribers(
          args.wait_subscribers,
          std::chrono::milliseconds(static_cast<int>(args.wait_subscribers_s * 1000)))) {
    std::cerr << "rig sweep: no telemetry subscriber on " << publisher.endpoint() << " within "
              << args.wait_subscribers_s << " s; going on without\n";
  }
}

// Prints how the run ended, where its results are and, when it did not
// complete, `again`: the command line that continues it. Returns the exit code.
int print_summary(const sweep::RunOutcome& outcome, std::int64_t run_id, std::size_t plan_size,
                  const db::store::Store& store, const std::string& again) {
  std::cout << "rig sweep: run " << run_id << " " << db::store::to_string(outcome.status)
            << (outcome.reason.empty() ? "" : ": " + outcome.reason) << "\n"
            << "  positions: " << outcome.positions_ok << " ok, " << outcome.positions_failed
            << " failed in this session; " << outcome.stored_total << " of " << plan_size
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

// What drives a run once the run exists: the controller, progress, the
// summary. `again` is the command line that continues a run that did not
// complete.
int drive_run(const SweepArgs& args, const sweep::SweepConfig& config, const sweep::SweepPlan& plan,
              motion::Bench& bench, vision::FrameSource& camera, db::store::Store& store,
              std::int64_t run_id, SweepLink& link, const std::string& again) {
  link.set_run(run_id);
  std::cout << "rig sweep: run " << run_id << " in " << store.path() << ", " << plan.size()
            << " positions (" << plan.description() << "), telemetry " << link.publisher.endpoint()
            << ", control " << link.control_endpoint() << std::endl;
  wait_for_subscribers(args, link.publisher);

  sweep::Controller controller(config, plan, bench, camera, store, run_id, link.control,
                               &link.publisher);
  if (args.retry_failed) controller.retake_failed_positions();
  // On a terminal: a progress bar with ETA redrawn on stderr, faults and
  // pauses as lines above it; otherwise one line per message on stdout.
  const bool terminal = telemetry::is_terminal(STDERR_FILENO) && !args.no_progress;
  telemetry::ProgressPrinter progress(terminal ? std::cerr : std::cout, terminal,
                                      telemetry::terminal_width(100, STDERR_FILENO));
  controller.set_observer([&](const nlohmann::json& message) { progress.update(message); });

  sweep::RunOutcome outcome;
  {
    const SweepLink::Attached attached(link, controller);
    outcome = controller.run();
  }
  return print_summary(outcome, run_id, plan.size(), store, again);
}

// rig sweep --replay RUN: the recorded run's plan, its saved frames, today's
// calibration, layout, geometry and solvers, into a new run of the same
// database. No bench and no camera are opened.
int run_replay(const SweepArgs& args, const sweep::SweepConfig& loaded, const std::string& database,
               SweepLink& link) {
  db::store::Store store = sweep::open_replay_database(database, loaded, args.replay_run);
  sweep::ReplayRun replay(loaded, store, args.replay_run);
  return drive_run(args, replay.config(), replay.plan(), replay.bench(), replay.frames(), store,
                   replay.run_id(), link,
                   "replay again: rig sweep " + loaded.sweep_file + " --db " + store.path() +
                       " --replay " + std::to_string(args.replay_run) +
                       " (a replay run is not resumed)");
}

// rig sweep [--resume RUN]: the camera first (a wrong calibration must stop
// the sweep before the bench moves), then the bench and the database, then
// the run is started or resumed (rig/sweep/run_start.hpp) and driven.
int run_on_bench(const SweepArgs& args, const sweep::SweepConfig& config,
                 const std::string& database, SweepLink& link) {
  const std::unique_ptr<vision::FrameSource> camera =
      sweep::open_sweep_camera(config, [](int attempt, const vision::CaptureError& e) {
        std::cerr << "rig sweep: camera attempt " << attempt << ": " << e.what()
                  << "; asking again (a controller that died may hold the camera until its "
                  << "heartbeat expires)\n";
      });
  const std::unique_ptr<motion::DrivenBench> driven =
      motion::open_bench(config.bench_url, config.bench_profile);
  motion::DrivenBench& bench = *driven;
  if (config.speed_mm_s) bench.set_speed(*config.speed_mm_s);
  db::store::Store store = sweep::open_run_database(database, config);

  const std::optional<sweep::StartedRun> run =
      args.resume_run > 0 ? sweep::resume_run(config, args.resume_run, bench, store, link.control,
                                              args.retry_failed)
                          : sweep::start_new_run(config, bench, store, link.control);
  if (!run) {
    std::cerr << "rig sweep: " << link.control.abort_reason()
              << " before the run started; nothing was recorded\n";
    return kExitFailure;
  }
  const vision::CameraIdentity id = camera->identity();
  store.record_camera(run->run_id, {camera->name(), id.device_id, id.vendor, id.model, id.serial,
                                    id.device_version});
  return drive_run(args, config, run->plan, bench, *camera, store, run->run_id, link,
                   "resume:    rig sweep " + config.sweep_file + " --db " + store.path() +
                       " --resume " + std::to_string(run->run_id));
}

int run_sweep(const SweepArgs& args) {
  if (args.replay_run > 0 && args.resume_run > 0)
    throw BadInput("--replay " + std::to_string(args.replay_run) + " and --resume " +
                   std::to_string(args.resume_run) +
                   " together: --replay measures a run's saved frames into a new run, --resume "
                   "continues a run on the bench; expected one of them");
  if (args.retry_failed && args.resume_run == 0)
    throw BadInput(
        "--retry-failed without --resume: it measures again the positions a resumed "
        "run stored as failed; expected --resume RUN --retry-failed");
  const sweep::SweepConfig config = sweep::load_sweep_config(args.sweep_file);
  const std::string database = args.database.empty() ? config.database_path : args.database;
  SweepLink link(config.telemetry);
  return args.replay_run > 0 ? run_replay(args, config, database, link)
                             : run_on_bench(args, config, database, link);
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
                  "stored as failed are kept, not measured again, unless --retry-failed)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--retry-failed", args->retry_failed,
                "With --resume: also measure again, in plan order, every position the run stored "
                "as failed (e.g. while the camera was lost), also of a run that completed with "
                "failed positions; each new measurement replaces the failed one, whose reason "
                "stays in the run's events (kind \"retake\")");
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
      "  rig sweep config/sweeps/ci.toml --db out/ci/run.db --resume 1 --retry-failed\n"
      "Replay run 1's saved frames (no rig needed) into a new run:\n"
      "  rig sweep config/sweeps/ci.toml --db out/ci/run.db --replay 1");
  cmd->callback(
      [&status, args] { status.code = run_command("sweep", [&] { return run_sweep(*args); }); });
}

}  // namespace rig::cli
