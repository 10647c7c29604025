#include "rig/sweep/run_start.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "config/json.hpp"
#include "rig/sweep/frame_files.hpp"
#include "rig/sweep/run_record.hpp"

namespace rig::sweep {
namespace {

db::store::Store open_store(const std::string& path, const SweepConfig& config) {
  db::store::StoreOptions options;
  options.durable_commits = config.durable_commits;
  options.record_store_time = true;
  return db::store::Store(path, options);
}

// Before the bench moves: the folder of the database's saved frames exists
// and takes new files. Bad input (the sweep file's save_frames) otherwise.
void check_frames_folder(const SweepConfig& config, const db::store::Store& store) {
  if (!config.frames_dir) return;
  try {
    prepare_frames_folder(database_frames_folder(*config.frames_dir, store.path()));
  } catch (const std::runtime_error& e) {
    throw SweepConfigError(config.sweep_file + ": capture.save_frames = \"" + *config.frames_dir +
                           "\": " + e.what());
  }
}

// Homes the bench if the sweep wants it homed and it is not; returns whether
// the run may start (no abort requested meanwhile).
bool home_if_needed(const SweepConfig& config, motion::Bench& bench,
                    const telemetry::ControlState& control) {
  const motion::BenchStatus status = bench.status();
  if (config.home_first && !status.homed) {
    // A drive that lost its homing (restarted, or moved before homing)
    // latches "not homed": homing is refused until the alarm is reset.
    if (status.alarm) bench.reset_alarm();
    bench.home();
    bench.wait_settled(std::chrono::milliseconds(config.bench_profile.timing.home_timeout_ms));
  }
  return !control.abort_requested();
}

// The run to resume, checked before anything moves.
db::store::Run resumable_run(const db::store::Store& store, std::int64_t run_id) {
  const std::string which = "--resume " + std::to_string(run_id);
  db::store::Run run;
  try {
    run = store.run(run_id);
  } catch (const db::store::StoreError& e) {
    throw RunMismatch(which + ": " + e.what());
  }
  const nlohmann::json stored_config = parse_stored_json(run.description.config_json);
  if (stored_config.is_object() && stored_config.contains("replay_of"))
    throw RunMismatch(which + ": run " + std::to_string(run.id) + " is a replay (of " +
                      config::excerpt_json(stored_config["replay_of"]) +
                      "); a replay is not resumed on the bench: replay the original run again "
                      "with --replay");
  return run;
}

std::shared_ptr<const RecordedRun> load_recorded(const db::store::Store& store,
                                                 std::int64_t run_id) {
  const std::string which = "--replay " + std::to_string(run_id);
  try {
    return std::make_shared<const RecordedRun>(RecordedRun::load(store, run_id));
  } catch (const db::store::StoreError& e) {
    throw RunMismatch(which + ": " + e.what());
  } catch (const PlanError& e) {
    throw RunMismatch(which + ": the run's stored plan: " + e.what());
  }
}

std::int64_t start_replay_run(const SweepConfig& config, db::store::Store& store,
                              const RecordedRun& recorded) {
  const nlohmann::json replay_of = {{"database", std::filesystem::absolute(store.path()).string()},
                                    {"run", recorded.run_id()}};
  const std::int64_t run_id =
      store.start_run(describe_run(config, recorded.plan(), {{"replay_of", replay_of}}));
  store.record_event(run_id, "start", "rig sweep --replay " + std::to_string(recorded.run_id()));
  return run_id;
}

}  // namespace

db::store::Store open_run_database(const std::string& path, const SweepConfig& config) {
  if (const auto parent = std::filesystem::path(path).parent_path(); !parent.empty())
    std::filesystem::create_directories(parent);
  return open_store(path, config);
}

std::optional<StartedRun> start_new_run(const SweepConfig& config, motion::Bench& bench,
                                        db::store::Store& store,
                                        const telemetry::ControlState& control) {
  check_frames_folder(config, store);
  if (!home_if_needed(config, bench, control)) return std::nullopt;
  return StartedRun{store.start_run(describe_run(config, config.plan)), config.plan};
}

std::optional<StartedRun> resume_run(const SweepConfig& config, std::int64_t run_id,
                                     motion::Bench& bench, db::store::Store& store,
                                     const telemetry::ControlState& control, bool retry_failed) {
  const db::store::Run run = resumable_run(store, run_id);
  const bool completed = run.status == db::store::RunStatus::kCompleted;
  if (completed && retry_failed) {
    const auto positions = store.positions(run.id);
    if (std::none_of(positions.begin(), positions.end(), [](const db::store::PositionRecord& p) {
          return p.status == db::store::PositionStatus::kFailed;
        }))
      throw RunMismatch("--resume " + std::to_string(run_id) + ": run " + std::to_string(run.id) +
                        " is completed and has no position stored as failed; there is nothing to "
                        "retry");
  }
  SweepPlan plan = plan_for_resume(run, config, completed && retry_failed);
  check_frames_folder(config, store);
  if (!home_if_needed(config, bench, control)) return std::nullopt;
  store.resume_run(run.id, retry_failed);
  store.record_event(run.id, "resume", "rig sweep --resume");
  return StartedRun{run.id, std::move(plan)};
}

db::store::Store open_replay_database(const std::string& path, const SweepConfig& config,
                                      std::int64_t recorded_run) {
  if (!std::filesystem::exists(path))
    throw RunMismatch("--replay " + std::to_string(recorded_run) + ": database " + path +
                      " does not exist; expected the database of the run to replay (--db)");
  return open_store(path, config);
}

ReplayRun::ReplayRun(const SweepConfig& loaded, db::store::Store& store, std::int64_t recorded_run)
    : recorded_(load_recorded(store, recorded_run)),
      config_(replay_config(loaded, *recorded_)),
      run_id_(start_replay_run(config_, store, *recorded_)),
      cursor_(std::make_shared<ReplayCursor>(recorded_)),
      bench_(cursor_),
      frames_(cursor_) {
  frames_.open();
}

}  // namespace rig::sweep
