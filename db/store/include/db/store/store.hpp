#pragma once
// db::store::Store: the run database of a sweep (docs/database.md).
//
// One SQLite file holds any number of runs. Each run stores what it was run
// with (configuration and plan as JSON, copies of the files it read with their
// SHA-256, versions, host) and, per plan position, one row in `positions` with
// its frames, detections, estimates and stage times. A position is written in
// one transaction (append_position), so after a crash, a kill -9 or a power
// loss (WAL journal, see StoreOptions::durable_commits) every position in the
// file is complete and `first_incomplete_position` says where a resumed sweep
// continues: nothing is lost, nothing is duplicated.
//
// The schema evolves through numbered migrations; the file's schema version is
// SQLite's `PRAGMA user_version` and the file is marked as a rig database by
// `PRAGMA application_id` (kApplicationId), so that another program's SQLite
// file is never mistaken for, or converted into, a run database.
//
// A Store is one SQLite connection: use it from one thread at a time. Several
// Stores (threads or processes) may open the same file; writers wait up to
// StoreOptions::busy_timeout_ms for each other, readers never block the writer.
//
// Errors: besides the errors each member lists for its input, every member
// throws StoreError, naming the file and the operation, when SQLite fails
// (the disk is full, the file is locked beyond the busy timeout, the file is
// damaged). A Store opened read_only throws StoreError from every writing
// member.

#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "db/store/records.hpp"

namespace db::store {

// Any failure of the database: the message names the file, the operation and
// SQLite's reason.
class StoreError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The file is not a rig run database (another SQLite file, not SQLite at all),
// or its schema is newer than this program knows.
class SchemaError : public StoreError {
 public:
  using StoreError::StoreError;
};

// append_position for a plan index that the run already has: refused, the
// file is unchanged.
class DuplicatePosition : public StoreError {
 public:
  using StoreError::StoreError;
};

struct StoreOptions {
  // How long a write waits for another connection's write lock before failing
  // with StoreError, milliseconds. Longer rides out a concurrent writer (a
  // second sweep on the same file); shorter surfaces a stuck writer sooner.
  // Readers in WAL mode never take the write lock.
  int busy_timeout_ms = 5000;
  // true: `synchronous = FULL`, each append_position is on disk when it
  // returns, so a power loss loses no committed position (one fsync of the
  // WAL per position). false: `synchronous = NORMAL`, still consistent after a
  // power loss (WAL) but the last positions may be rolled back and are then
  // measured again on resume; a crash of the process alone loses nothing either way.
  bool durable_commits = true;
  // true: open an existing run database for reading only (a report): never
  // creates, migrates or writes the file. Throws StoreError if the file does
  // not exist, SchemaError if it is not a rig database or its schema is not
  // exactly kSchemaVersion (older files are migrated by any writing open).
  bool read_only = false;
  // true: append_position stores one more stage time, "store": the seconds
  // spent writing the position's rows, up to (not including) the commit and
  // its fsync. A sweep's per-stage times then include the database's share.
  bool record_store_time = false;
};

// The run status stored as `text` in runs.status of the database at `path`
// (the inverse of to_string(RunStatus)). Throws StoreError naming the file
// and the text if it is none of to_string's.
RunStatus run_status_from_text(const std::string& path, const std::string& text);

// Version of the SQLite library linked into this program ("3.40.1"), for a
// run's library_versions_json: rig does not see SQLite itself.
std::string sqlite_library_version();

class Store {
 public:
  // Schema version this code creates and reads (the number of migrations).
  static constexpr int kSchemaVersion = 5;
  // PRAGMA application_id of a rig run database: "RIGD" in ASCII.
  static constexpr std::int32_t kApplicationId = 0x52494744;

  // Opens the database file at path, creating it (or filling an empty file)
  // and migrating it to kSchemaVersion. Throws SchemaError if the file is not
  // SQLite, is some other program's SQLite database, or has a schema newer
  // than kSchemaVersion; StoreError if it cannot be opened or switched to WAL.
  explicit Store(const std::string& path, StoreOptions options = {});
  ~Store();
  // A moved-from Store may only be destroyed or assigned to.
  Store(Store&&) noexcept;
  Store& operator=(Store&&) noexcept;
  Store(const Store&) = delete;
  Store& operator=(const Store&) = delete;

  // The path the Store was opened with, as given.
  const std::string& path() const;

  // Records a new run with status running and started_at now; returns its id.
  // Fills the SHA-256 of each stored file. Throws StoreError naming the field
  // if a JSON field does not parse, library_versions_json is not an object, or
  // plan_size is negative.
  std::int64_t start_run(RunDescription description);

  // Ends a running run: status completed, aborted or failed, with a reason
  // (required for aborted and failed), and ended_at now. Throws StoreError if
  // the run does not exist, is not running, or status is kRunning.
  void finish_run(std::int64_t run_id, RunStatus status, const std::string& reason);

  // Puts an aborted or failed run, or one left running by a crash, back to
  // running for `rig sweep --resume`; clears ended_at and the reason. With
  // completed_with_failed, also a completed run that has a position stored as
  // failed (`--resume RUN --retry-failed`). Throws StoreError for an unknown
  // run or any other completed one.
  void resume_run(std::int64_t run_id, bool completed_with_failed = false);

  // Every run, oldest first, with its stored files: runs are few and small
  // next to their positions.
  std::vector<Run> runs() const;
  // One run; throws StoreError if there is no run with that id.
  Run run(std::int64_t run_id) const;

  // Writes a position with all its stage times, frames, detections and
  // estimates in one transaction: afterwards the file holds all of it, or, if
  // this throws (or the process dies), none of it. Throws DuplicatePosition if
  // the run already has position.plan_index; StoreError if the run does not
  // exist, is not running, or plan_index is outside [0, plan_size).
  void append_position(std::int64_t run_id, const PositionRecord& position);

  // A failed position measured again (`rig sweep --resume RUN --retry-failed`):
  // in one transaction, the run's position at position.plan_index, which must
  // be stored as failed, is deleted with everything it held and `position` is
  // written in its place. Either the new position is stored or the failed
  // one is still there. The failure itself stays recorded in the run's events
  // (the controller records a "camera"/"settle" fault and a "retake" event).
  // Throws StoreError naming the run and plan index if the run has no failed
  // position there (none, or one stored ok), and as append_position.
  void retake_failed_position(std::int64_t run_id, const PositionRecord& position);

  // Records the camera that takes the run's frames (table run_camera, one
  // per run): a resumed run records the camera it was resumed with, replacing
  // the earlier one. Throws StoreError for an unknown run.
  void record_camera(std::int64_t run_id, const RunCamera& camera);

  // Records a fault, pause or resume of the run (RunEvent kinds), with the
  // store's clock; its own transaction. Throws StoreError for an unknown run
  // or an empty kind.
  void record_event(std::int64_t run_id, const std::string& kind, const std::string& message,
                    std::optional<std::int64_t> plan_index = std::nullopt);
  // The run's events, oldest first. Throws StoreError for an unknown run.
  std::vector<RunEvent> events(std::int64_t run_id) const;

  // Plan indices the run has (ok or failed), ascending. Throws StoreError for
  // an unknown run.
  std::vector<std::int64_t> completed_position_indices(std::int64_t run_id) const;
  // The smallest plan index in [0, plan_size) that the run does not have;
  // nullopt when every position is stored. Throws StoreError for an unknown run.
  std::optional<std::int64_t> first_incomplete_position(std::int64_t run_id) const;

  // The run's positions by plan index, with stage times, distance bounds and
  // visible markers but WITHOUT frames (frames is empty): what a report
  // iterates over, read in one snapshot. Use position() for one position in
  // full. Empty for an unknown run.
  std::vector<PositionRecord> positions(std::int64_t run_id) const;
  // One position with its frames, detections and estimates in the order they
  // were appended. Throws StoreError if the run has no such position.
  PositionRecord position(std::int64_t run_id, std::int64_t plan_index) const;

  // Every estimate of one solver in a run (all scopes, every detector:
  // EstimateRecord::detector tells them apart), by plan index, frame index
  // and order of appending, with the position's true distance. Empty for an
  // unknown run or solver.
  std::vector<EstimateRow> estimates(std::int64_t run_id, const std::string& solver) const;
  // Names of the solvers that have estimates in the run, sorted; empty for an
  // unknown run.
  std::vector<std::string> solvers(std::int64_t run_id) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace db::store
