#include "schema.hpp"

#include <string>

namespace db::store::schema {
namespace {

// Migration N takes a file from schema version N-1 to N. Append new ones;
// never edit a migration that has shipped (files in the field were made by it).
//
// Query paths the indexes serve (db::store::Store and the reports):
//   positions by run and plan index  -> UNIQUE (run_id, plan_index)
//   frames of a position             -> UNIQUE (position_id, frame_index)
//   estimates by run and solver      -> positions(run_id) -> frames(position_id)
//                                       -> estimates (frame_id, detector, solver)
//   detections of a frame            -> detections (frame_id)
//   bounds, visible markers of a position -> PRIMARY KEY (position_id, ...)
//   events of a run                  -> run_events (run_id, id)
// Child rows reference their parent with ON DELETE CASCADE so that deleting a
// run deletes everything measured in it.
constexpr const char* kMigrations[] = {
    // 1: runs, positions, frames, detections, estimates (docs/database.md).
    R"sql(
CREATE TABLE runs (
  id INTEGER PRIMARY KEY,
  started_at TEXT NOT NULL,
  ended_at TEXT,
  status TEXT NOT NULL CHECK (status IN ('running', 'completed', 'aborted', 'failed')),
  status_reason TEXT NOT NULL DEFAULT '',
  config_json TEXT NOT NULL,
  plan_json TEXT NOT NULL,
  plan_size INTEGER NOT NULL CHECK (plan_size >= 0),
  software_version TEXT NOT NULL,
  library_versions_json TEXT NOT NULL,
  host TEXT NOT NULL
);
CREATE TABLE run_files (
  run_id INTEGER NOT NULL REFERENCES runs (id) ON DELETE CASCADE,
  role TEXT NOT NULL CHECK (role IN ('sweep_file', 'camera_calibration', 'target_layout',
                                     'rig_geometry', 'bench_profile')),
  path TEXT NOT NULL,
  content BLOB NOT NULL,
  sha256 TEXT NOT NULL CHECK (length(sha256) = 64),
  PRIMARY KEY (run_id, role)
);
CREATE TABLE positions (
  id INTEGER PRIMARY KEY,
  run_id INTEGER NOT NULL REFERENCES runs (id) ON DELETE CASCADE,
  plan_index INTEGER NOT NULL CHECK (plan_index >= 0),
  commanded_x_mm REAL NOT NULL,
  commanded_y_mm REAL NOT NULL,
  measured_x_mm REAL,
  measured_y_mm REAL,
  true_distance_m REAL,
  settle_time_s REAL NOT NULL,
  status TEXT NOT NULL CHECK (status IN ('ok', 'failed')),
  failure_reason TEXT NOT NULL DEFAULT '',
  UNIQUE (run_id, plan_index)
);
CREATE TABLE stage_times (
  position_id INTEGER NOT NULL REFERENCES positions (id) ON DELETE CASCADE,
  seq INTEGER NOT NULL,
  stage TEXT NOT NULL,
  seconds REAL NOT NULL,
  PRIMARY KEY (position_id, seq)
) WITHOUT ROWID;
CREATE TABLE frames (
  id INTEGER PRIMARY KEY,
  position_id INTEGER NOT NULL REFERENCES positions (id) ON DELETE CASCADE,
  frame_index INTEGER NOT NULL CHECK (frame_index >= 0),
  camera_timestamp_ns INTEGER,
  host_timestamp_ns INTEGER NOT NULL,
  source TEXT NOT NULL,
  image_path TEXT,
  image_sha256 TEXT CHECK (image_sha256 IS NULL OR length(image_sha256) = 64),
  UNIQUE (position_id, frame_index)
);
CREATE TABLE detections (
  id INTEGER PRIMARY KEY,
  frame_id INTEGER NOT NULL REFERENCES frames (id) ON DELETE CASCADE,
  marker_id INTEGER NOT NULL,
  rotation INTEGER NOT NULL CHECK (rotation BETWEEN 0 AND 3),
  a_x_px REAL NOT NULL, a_y_px REAL NOT NULL,
  b_x_px REAL NOT NULL, b_y_px REAL NOT NULL,
  c_x_px REAL NOT NULL, c_y_px REAL NOT NULL,
  d_x_px REAL NOT NULL, d_y_px REAL NOT NULL,
  contrast REAL NOT NULL,
  bits_corrected INTEGER NOT NULL,
  edge_fit_residual_px REAL NOT NULL
);
CREATE INDEX detections_by_frame ON detections (frame_id);
CREATE TABLE estimates (
  id INTEGER PRIMARY KEY,
  frame_id INTEGER NOT NULL REFERENCES frames (id) ON DELETE CASCADE,
  solver TEXT NOT NULL,
  scope TEXT NOT NULL,
  r00 REAL NOT NULL, r01 REAL NOT NULL, r02 REAL NOT NULL,
  r10 REAL NOT NULL, r11 REAL NOT NULL, r12 REAL NOT NULL,
  r20 REAL NOT NULL, r21 REAL NOT NULL, r22 REAL NOT NULL,
  tx_m REAL NOT NULL, ty_m REAL NOT NULL, tz_m REAL NOT NULL,
  distance_m REAL NOT NULL,
  reprojection_error_px REAL NOT NULL,
  generalization_error_px REAL,
  iterations INTEGER NOT NULL,
  converged INTEGER NOT NULL CHECK (converged IN (0, 1)),
  termination TEXT NOT NULL,
  time_us REAL NOT NULL,
  ambiguity_ratio REAL
);
CREATE INDEX estimates_by_frame_solver ON estimates (frame_id, solver);
)sql",
    // 2: what a report needs beyond the measurements (truth per position,
    // bounds, markers in view) and the faults of a sweep, all written by the
    // controller.
    R"sql(
ALTER TABLE positions ADD COLUMN true_viewing_angle_deg REAL;
CREATE TABLE distance_bounds (
  position_id INTEGER NOT NULL REFERENCES positions (id) ON DELETE CASCADE,
  scope TEXT NOT NULL,
  distance_sd_m_per_px REAL NOT NULL CHECK (distance_sd_m_per_px >= 0),
  PRIMARY KEY (position_id, scope)
) WITHOUT ROWID;
CREATE TABLE visible_markers (
  position_id INTEGER NOT NULL REFERENCES positions (id) ON DELETE CASCADE,
  marker_id INTEGER NOT NULL,
  side_px REAL NOT NULL CHECK (side_px > 0),
  PRIMARY KEY (position_id, marker_id)
) WITHOUT ROWID;
CREATE TABLE run_events (
  id INTEGER PRIMARY KEY,
  run_id INTEGER NOT NULL REFERENCES runs (id) ON DELETE CASCADE,
  at TEXT NOT NULL,
  plan_index INTEGER,
  kind TEXT NOT NULL,
  message TEXT NOT NULL
);
CREATE INDEX run_events_by_run ON run_events (run_id, id);
)sql",
    // 3: the camera that took the run's frames, as it identified itself
    // (GenICam Device* features, or what V4L2 reports), so that a report can
    // name it and tell the simulated rig from a bench.
    R"sql(
CREATE TABLE run_camera (
  run_id INTEGER PRIMARY KEY REFERENCES runs (id) ON DELETE CASCADE,
  source TEXT NOT NULL,
  device_id TEXT NOT NULL,
  vendor TEXT NOT NULL,
  model TEXT NOT NULL,
  serial TEXT NOT NULL,
  device_version TEXT NOT NULL
);
)sql",
    // 4: the true pose per position (rotation row-major, translation in
    // metres; NULL when unknown and in positions stored before it), so that
    // a report can give per-axis translation and rotation errors.
    R"sql(
ALTER TABLE positions ADD COLUMN true_r00 REAL;
ALTER TABLE positions ADD COLUMN true_r01 REAL;
ALTER TABLE positions ADD COLUMN true_r02 REAL;
ALTER TABLE positions ADD COLUMN true_r10 REAL;
ALTER TABLE positions ADD COLUMN true_r11 REAL;
ALTER TABLE positions ADD COLUMN true_r12 REAL;
ALTER TABLE positions ADD COLUMN true_r20 REAL;
ALTER TABLE positions ADD COLUMN true_r21 REAL;
ALTER TABLE positions ADD COLUMN true_r22 REAL;
ALTER TABLE positions ADD COLUMN true_tx_m REAL;
ALTER TABLE positions ADD COLUMN true_ty_m REAL;
ALTER TABLE positions ADD COLUMN true_tz_m REAL;
)sql",
    // 5: the detector (vision/detectors.hpp registry name) that found each
    // detection and whose corners each estimate was solved from; a sweep
    // runs several, and each run names its primary one (whose corners
    // calibration and external estimators use). Rows stored before it are
    // rig's own detector's. Each
    // detection's RMS distance from its true corners (the layout's corners
    // projected through the run's camera at the true pose; NULL when the
    // true pose is unknown and in rows stored before it).
    R"sql(
ALTER TABLE runs ADD COLUMN primary_detector TEXT NOT NULL DEFAULT 'rig';
ALTER TABLE detections ADD COLUMN detector TEXT NOT NULL DEFAULT 'rig';
ALTER TABLE detections ADD COLUMN true_corner_rms_px REAL;
ALTER TABLE estimates ADD COLUMN detector TEXT NOT NULL DEFAULT 'rig';
DROP INDEX estimates_by_frame_solver;
CREATE INDEX estimates_by_frame_detector_solver ON estimates (frame_id, detector, solver);
)sql",
};

constexpr int kMigrationCount = static_cast<int>(sizeof(kMigrations) / sizeof(kMigrations[0]));
static_assert(kMigrationCount == Store::kSchemaVersion,
              "Store::kSchemaVersion is the number of migrations");

std::int64_t pragma_int(sqlite::Connection& connection, const char* pragma) {
  sqlite::Statement statement(connection, std::string("PRAGMA ") + pragma);
  statement.step();
  return statement.get_int64(0);
}

// Reads the markers of the file and refuses it unless it is empty or ours at
// a version we know. Returns the file's schema version (0 when empty).
// `expected` says what the caller can use, for the message.
int check_file(sqlite::Connection& connection, const char* expected) {
  const std::string& path = connection.path();
  std::int64_t objects = 0;
  std::int64_t application_id = 0;
  std::int64_t version = 0;
  try {
    // The first read of the file: this is where SQLite finds out whether the
    // file is a database at all.
    sqlite::Statement count(connection, "SELECT count(*) FROM sqlite_schema");
    count.step();
    objects = count.get_int64(0);
    application_id = pragma_int(connection, "application_id");
    version = pragma_int(connection, "user_version");
  } catch (const StoreError& e) {
    if (sqlite3_errcode(connection.handle()) == SQLITE_NOTADB) {
      throw SchemaError(path + ": not a SQLite database (" + sqlite3_errmsg(connection.handle()) +
                        "); expected " + expected);
    }
    throw;
  }
  if (objects == 0 && application_id == 0 && version == 0) return 0;
  if (application_id != Store::kApplicationId) {
    throw SchemaError(path + ": a SQLite database of another program (application_id " +
                      std::to_string(application_id) + ", " + std::to_string(objects) +
                      " schema objects), not a rig run database (application_id " +
                      std::to_string(Store::kApplicationId) + "); refusing to modify it");
  }
  if (version > Store::kSchemaVersion) {
    throw SchemaError(path + ": run database schema version " + std::to_string(version) +
                      " is newer than this program's version " +
                      std::to_string(Store::kSchemaVersion) +
                      "; open it with a newer rig (it is left unchanged)");
  }
  return static_cast<int>(version);
}

}  // namespace

void open_and_migrate(sqlite::Connection& connection, const StoreOptions& options) {
  sqlite3_busy_timeout(connection.handle(), options.busy_timeout_ms);
  // Check before anything writes: another program's file must not even be
  // switched to WAL.
  const int found =
      check_file(connection, options.read_only ? "a rig run database (written by rig sweep)"
                                               : "a rig run database or a new or empty file");
  if (options.read_only) {
    if (found == 0) {
      throw SchemaError(connection.path() +
                        ": an empty file, not a rig run database (written by rig sweep)");
    }
    if (found != Store::kSchemaVersion) {
      throw SchemaError(connection.path() + ": run database schema version " +
                        std::to_string(found) + " is older than this program's version " +
                        std::to_string(Store::kSchemaVersion) +
                        "; it is opened read-only, so it cannot be migrated: open it once with a "
                        "writing command (rig sweep --resume) or a copy of it");
    }
    connection.exec("PRAGMA query_only = ON");
    return;
  }

  sqlite::Statement wal(connection, "PRAGMA journal_mode = WAL");
  wal.step();
  if (wal.get_text(0) != "wal") {
    throw StoreError(connection.path() + ": cannot use the WAL journal (journal_mode is \"" +
                     wal.get_text(0) + "\"); a run database must be a file on a local disk");
  }
  wal.reset();
  connection.exec(options.durable_commits ? "PRAGMA synchronous = FULL"
                                          : "PRAGMA synchronous = NORMAL");
  connection.exec("PRAGMA foreign_keys = ON");

  // Again under the write lock: another process may have migrated the file
  // between the check above and now.
  sqlite::Transaction transaction(connection);
  const int version = check_file(connection, "a rig run database or a new or empty file");
  if (version == Store::kSchemaVersion) return;  // nothing to do; rolls back the empty transaction
  if (version == 0) {
    connection.exec("PRAGMA application_id = " + std::to_string(Store::kApplicationId));
  }
  for (int next = version + 1; next <= Store::kSchemaVersion; ++next) {
    connection.exec(kMigrations[next - 1]);
  }
  connection.exec("PRAGMA user_version = " + std::to_string(Store::kSchemaVersion));
  transaction.commit();
}

}  // namespace db::store::schema
