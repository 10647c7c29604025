// Starting the run a sweep measures into (docs/data-flow.md, docs/database.md):
// a new run of the sweep file's plan, a resumed run (`rig sweep --resume`), or
// a replay of a recorded run's saved frames (`rig sweep --replay`). Each
// checks what it can before anything moves or is written; a new or resumed
// run homes the bench before anything is recorded. The Controller then
// measures the run.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "db/store/store.hpp"
#include "motion/bench.hpp"
#include "rig/sweep/replay.hpp"
#include "rig/sweep/sweep_config.hpp"
#include "rig/sweep/sweep_plan.hpp"
#include "rig/telemetry/telemetry.hpp"
#include "vision/frame_source.hpp"

namespace rig::sweep {

// A run that exists in the store and is running, ready for the Controller.
struct StartedRun {
  std::int64_t run_id = 0;
  // The plan the Controller measures: the sweep file's for a new run, the
  // one the run stored for a resumed run.
  SweepPlan plan;
};

// Opens the run database at `path` for a sweep, creating it and its folder
// when missing: commits as config.durable_commits says, and the store times
// its own share of every position (StoreOptions::record_store_time). Throws
// db::store::SchemaError for a file that is not a rig database,
// db::store::StoreError when it cannot be opened, std::filesystem's error
// when the folder cannot be created.
db::store::Store open_run_database(const std::string& path, const SweepConfig& config);

// A new run of config.plan: homes the bench first when config.home_first and
// the bench is not homed (homing is needed once per power-up of the drive;
// a homed bench is not driven home and back), then records the run
// (describe_run). Returns nothing, and records nothing, when `control` had an
// abort requested by then. Throws motion::BenchError from homing (within the
// profile's home_timeout_ms), SweepConfigError from describe_run,
// db::store::StoreError.
std::optional<StartedRun> start_new_run(const SweepConfig& config, motion::Bench& bench,
                                        db::store::Store& store,
                                        const telemetry::ControlState& control);

// Resumes run `run_id` of `store` from its first missing position. Before
// the bench moves, checks that the run exists, is not a replay (a replay is
// not resumed on the bench) and may be resumed with the files config read
// (plan_for_resume); then homes the bench as start_new_run does; then puts
// the run back to running and records a "resume" event. Returns the run with
// its stored plan, or nothing (nothing recorded) when `control` had an abort
// requested by then. Throws RunMismatch "--resume N: ..." for an unknown run
// or a replay, what plan_for_resume throws, then as start_new_run.
// With retry_failed (`--retry-failed`), a completed run that has positions
// stored as failed is resumed too (RunMismatch for one that has none).
std::optional<StartedRun> resume_run(const SweepConfig& config, std::int64_t run_id,
                                     motion::Bench& bench, db::store::Store& store,
                                     const telemetry::ControlState& control,
                                     bool retry_failed = false);

// Opens the database holding the run to replay, as open_run_database does,
// but only if it exists: a replay must not create an empty database. Throws
// RunMismatch "--replay N: database PATH does not exist; ..." otherwise.
db::store::Store open_replay_database(const std::string& path, const SweepConfig& config,
                                      std::int64_t recorded_run);

// A replay of run `recorded_run` (`rig sweep --replay RUN`, replay.hpp): the
// recorded run's plan and read-backs, its saved frames, and the loaded sweep
// file's calibration, layout, geometry and solvers (replay_config), measured
// into a new run of the same database. No bench and no camera are opened.
class ReplayRun {
 public:
  // Loads the recorded run, derives the replay's configuration, then records
  // the new run, with {"replay_of": {"database": absolute path, "run": N}} in
  // its configuration and a "start" event. Throws RunMismatch
  // "--replay N: ..." for an unknown run or a damaged stored plan, and what
  // replay_config throws; nothing is recorded then. `store` must outlive
  // the ReplayRun.
  ReplayRun(const SweepConfig& loaded, db::store::Store& store, std::int64_t recorded_run);
  ReplayRun(const ReplayRun&) = delete;
  ReplayRun& operator=(const ReplayRun&) = delete;

  std::int64_t recorded_run() const { return recorded_->run_id(); }
  // The new run.
  std::int64_t run_id() const { return run_id_; }
  // The configuration the replay measures with (replay_config).
  const SweepConfig& config() const { return config_; }
  // The recorded run's plan.
  const SweepPlan& plan() const { return recorded_->plan(); }
  // The recorded run as a bench and an open frame source, for the Controller.
  motion::Bench& bench() { return bench_; }
  vision::FrameSource& frames() { return frames_; }

 private:
  std::shared_ptr<const RecordedRun> recorded_;
  SweepConfig config_;
  std::int64_t run_id_ = 0;
  std::shared_ptr<ReplayCursor> cursor_;
  ReplayBench bench_;
  ReplayFrames frames_;
};

}  // namespace rig::sweep
