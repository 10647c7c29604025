// Opening files: a new or empty file is migrated to the current schema; a
// newer schema, another program's SQLite file and a file that is not SQLite
// are refused with an error naming the file, and left untouched.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <fstream>
#include <string>

#include "db/store/store.hpp"
#include "store_fixture.hpp"

namespace {

using db_test::ScratchDir;

// Raw access to a file, independent of db::store::Store, to prepare and inspect it.
class RawDb {
 public:
  explicit RawDb(const std::string& path) {
    if (sqlite3_open(path.c_str(), &db_) != SQLITE_OK) throw std::runtime_error("open " + path);
  }
  ~RawDb() { sqlite3_close(db_); }
  void exec(const std::string& sql) {
    char* error = nullptr;
    if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
      const std::string message = error ? error : "?";
      sqlite3_free(error);
      throw std::runtime_error(sql + ": " + message);
    }
  }
  std::string text(const std::string& sql) {
    sqlite3_stmt* statement = nullptr;
    sqlite3_prepare_v2(db_, sql.c_str(), -1, &statement, nullptr);
    std::string value;
    if (sqlite3_step(statement) == SQLITE_ROW) {
      const auto* t = sqlite3_column_text(statement, 0);
      value = t ? reinterpret_cast<const char*>(t) : "";
    }
    sqlite3_finalize(statement);
    return value;
  }

 private:
  sqlite3* db_ = nullptr;
};

std::string message_of(const std::string& path) {
  try {
    db::store::Store store(path);
  } catch (const db::store::SchemaError& e) {
    return e.what();
  }
  return "(no SchemaError)";
}

TEST(StoreSchema, MigratesAnEmptyFileToTheCurrentSchema) {
  ScratchDir dir;
  const std::string path = dir.file("empty.db");
  std::ofstream(path).close();  // zero bytes: SQLite treats it as an empty database
  { db::store::Store store(path); }
  RawDb raw(path);
  EXPECT_EQ(raw.text("PRAGMA user_version"), std::to_string(db::store::Store::kSchemaVersion));
  EXPECT_EQ(raw.text("PRAGMA application_id"), std::to_string(db::store::Store::kApplicationId));
  EXPECT_EQ(raw.text("PRAGMA journal_mode"), "wal");
  for (const char* table :
       {"runs", "run_files", "positions", "stage_times", "frames", "detections", "estimates"}) {
    EXPECT_EQ(raw.text(std::string("SELECT count(*) FROM sqlite_schema WHERE type = 'table' AND "
                                   "name = '") +
                       table + "'"),
              "1")
        << table;
  }
  EXPECT_EQ(raw.text("PRAGMA integrity_check"), "ok");
}

TEST(StoreSchema, CreatesAMissingFileAndReopensItWithItsRuns) {
  ScratchDir dir;
  const std::string path = dir.file("new.db");
  std::int64_t id = 0;
  {
    db::store::Store store(path);
    id = store.start_run(db_test::make_run_description(3));
  }
  db::store::Store reopened(path);
  ASSERT_EQ(reopened.runs().size(), 1u);
  EXPECT_EQ(reopened.runs().front().id, id);
}

TEST(StoreSchema, RefusesANewerSchemaNamingTheFileAndBothVersions) {
  ScratchDir dir;
  const std::string path = dir.file("future.db");
  { db::store::Store store(path); }
  RawDb(path).exec("PRAGMA user_version = 7");
  const std::string message = message_of(path);
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("version 7"), std::string::npos) << message;
  EXPECT_NE(message.find("version " + std::to_string(db::store::Store::kSchemaVersion)),
            std::string::npos)
      << message;
  EXPECT_EQ(RawDb(path).text("PRAGMA user_version"), "7");
}

TEST(StoreSchema, RefusesAnotherProgramsSqliteFileWithoutChangingIt) {
  ScratchDir dir;
  const std::string path = dir.file("other.db");
  RawDb(path).exec("CREATE TABLE songs (title TEXT); INSERT INTO songs VALUES ('x')");
  const std::string message = message_of(path);
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("not a rig run database"), std::string::npos) << message;
  RawDb raw(path);
  EXPECT_EQ(raw.text("PRAGMA journal_mode"), "delete");  // not switched to WAL
  EXPECT_EQ(raw.text("SELECT count(*) FROM sqlite_schema"), "1");
}

TEST(StoreSchema, RefusesAFileThatIsNotSqlite) {
  ScratchDir dir;
  const std::string path = dir.file("notes.db");
  std::ofstream(path) << std::string(4096, 'x') << "these are notes, not a database\n";
  const std::string message = message_of(path);
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("not a SQLite database"), std::string::npos) << message;
}

TEST(StoreSchema, RefusesAFileThatCannotBeOpened) {
  ScratchDir dir;
  EXPECT_THROW(db::store::Store(dir.file("no/such/dir/run.db")), db::store::StoreError);
}

}  // namespace

namespace {

// Migration 4's additions, removed from a current file.
void drop_true_pose_columns(RawDb& raw) {
  for (const char* c : {"true_r00", "true_r01", "true_r02", "true_r10", "true_r11", "true_r12",
                        "true_r20", "true_r21", "true_r22", "true_tx_m", "true_ty_m", "true_tz_m"})
    raw.exec(std::string("ALTER TABLE positions DROP COLUMN ") + c);
}

// Undoes migration 5 (the detector of each row, the run's primary detector,
// the true-corner RMS): the file as schema 4 left it.
void drop_detector_columns(RawDb& raw) {
  raw.exec(
      "DROP INDEX estimates_by_frame_detector_solver; "
      "CREATE INDEX estimates_by_frame_solver ON estimates (frame_id, solver); "
      "ALTER TABLE estimates DROP COLUMN detector; "
      "ALTER TABLE detections DROP COLUMN detector; "
      "ALTER TABLE detections DROP COLUMN true_corner_rms_px; "
      "ALTER TABLE runs DROP COLUMN primary_detector");
}

// A file as schema version 1 wrote it: migration 2's additions removed from a
// current file, with one position in it.
std::string make_version1_file(const ScratchDir& dir) {
  const std::string path = dir.file("v1.db");
  {
    db::store::Store store(path);
    const std::int64_t run = store.start_run(db_test::make_run_description(4));
    store.append_position(run, db_test::make_position(0));
  }
  RawDb raw(path);
  raw.exec(
      "DROP TABLE run_camera; DROP TABLE distance_bounds; DROP TABLE visible_markers; "
      "DROP TABLE run_events; "
      "ALTER TABLE positions DROP COLUMN true_viewing_angle_deg; PRAGMA user_version = 1");
  drop_true_pose_columns(raw);
  drop_detector_columns(raw);
  return path;
}

}  // namespace

TEST(StoreSchema, MigratesAVersion1FileKeepingItsPositions) {
  ScratchDir dir;
  const std::string path = make_version1_file(dir);
  db::store::Store store(path);
  EXPECT_EQ(RawDb(path).text("PRAGMA user_version"),
            std::to_string(db::store::Store::kSchemaVersion));
  const db::store::PositionRecord expected = db_test::make_position(0);
  const db::store::PositionRecord back = store.position(1, 0);
  // What version 1 stored is intact; what it could not store is absent.
  EXPECT_EQ(back.frames, expected.frames);
  EXPECT_EQ(back.stage_times, expected.stage_times);
  EXPECT_FALSE(back.true_viewing_angle_deg.has_value());
  EXPECT_TRUE(back.distance_bounds.empty());
  EXPECT_TRUE(back.visible_markers.empty());
  EXPECT_FALSE(back.true_pose.has_value());
  // And the migrated file takes positions with the new fields.
  store.append_position(1, db_test::make_position(1));
  EXPECT_EQ(store.position(1, 1), db_test::make_position(1));
  EXPECT_EQ(RawDb(path).text("PRAGMA integrity_check"), "ok");
}

// A version 2 file (before run_camera) keeps its runs, which read as
// "camera not recorded", and takes the camera of a new run.
TEST(StoreSchema, MigratesAVersion2FileWhoseRunsHaveNoCamera) {
  ScratchDir dir;
  const std::string path = dir.file("v2.db");
  {
    db::store::Store store(path);
    store.start_run(db_test::make_run_description(4));
  }
  {
    RawDb raw(path);
    raw.exec("DROP TABLE run_camera; PRAGMA user_version = 2");
    drop_true_pose_columns(raw);
    drop_detector_columns(raw);
  }
  db::store::Store store(path);
  EXPECT_EQ(RawDb(path).text("PRAGMA user_version"),
            std::to_string(db::store::Store::kSchemaVersion));
  EXPECT_FALSE(store.run(1).camera.has_value());
  const std::int64_t run = store.start_run(db_test::make_run_description(4));
  store.record_camera(
      run, {"gige:127.0.0.1", "rig-rig-sim-1", "rig", "rig-sim", "1", "realism default"});
  ASSERT_TRUE(store.run(run).camera.has_value());
  EXPECT_EQ(store.run(run).camera->model, "rig-sim");
  EXPECT_FALSE(store.run(1).camera.has_value());
}

// A version 3 file (before the true pose) keeps its positions, which read
// without a true pose, and takes positions with one.
TEST(StoreSchema, MigratesAVersion3FileWhosePositionsHaveNoTruePose) {
  ScratchDir dir;
  const std::string path = dir.file("v3.db");
  {
    db::store::Store store(path);
    const std::int64_t run = store.start_run(db_test::make_run_description(4));
    store.append_position(run, db_test::make_position(0));
  }
  {
    RawDb raw(path);
    drop_true_pose_columns(raw);
    drop_detector_columns(raw);
    raw.exec("PRAGMA user_version = 3");
  }
  db::store::Store store(path);
  EXPECT_EQ(RawDb(path).text("PRAGMA user_version"),
            std::to_string(db::store::Store::kSchemaVersion));
  db::store::PositionRecord expected = db_test::make_position(0);
  expected.true_pose.reset();
  EXPECT_EQ(store.position(1, 0), expected);
  store.append_position(1, db_test::make_position(1));
  const db::store::PositionRecord back = store.position(1, 1);
  ASSERT_TRUE(back.true_pose.has_value());
  EXPECT_EQ(back, db_test::make_position(1));
  EXPECT_EQ(RawDb(path).text("PRAGMA integrity_check"), "ok");
}

// A version 4 file (one detector per run, rig's) keeps its detections and
// estimates, which read as rig's detector's, its runs' primary detector is
// rig's, and the migrated file takes rows of other detectors.
TEST(StoreSchema, MigratesAVersion4FileWhoseRowsAreRigsDetectors) {
  ScratchDir dir;
  const std::string path = dir.file("v4.db");
  {
    db::store::Store store(path);
    const std::int64_t run = store.start_run(db_test::make_run_description(4));
    store.append_position(run, db_test::make_position(0));
  }
  {
    RawDb raw(path);
    drop_detector_columns(raw);
    raw.exec("PRAGMA user_version = 4");
  }
  db::store::Store store(path);
  EXPECT_EQ(RawDb(path).text("PRAGMA user_version"),
            std::to_string(db::store::Store::kSchemaVersion));
  EXPECT_EQ(store.run(1).description.primary_detector, "rig");
  const db::store::PositionRecord back = store.position(1, 0);
  EXPECT_EQ(back, db_test::make_position(0));
  ASSERT_FALSE(back.frames.empty());
  ASSERT_FALSE(back.frames[0].detections.empty());
  ASSERT_FALSE(back.frames[0].estimates.empty());
  for (const auto& f : back.frames) {
    for (const auto& d : f.detections) {
      EXPECT_EQ(d.detector, "rig");
      EXPECT_FALSE(d.true_corner_rms_px.has_value());
    }
    for (const auto& e : f.estimates)
      EXPECT_EQ(e.detector, "rig");
  }
  // Rows of another detector, with a true-corner RMS, round-trip.
  db::store::RunDescription d = db_test::make_run_description(4);
  d.primary_detector = "aruco:subpix";
  const std::int64_t run = store.start_run(d);
  db::store::PositionRecord p = db_test::make_position(0);
  for (auto& f : p.frames) {
    for (auto& det : f.detections) {
      det.detector = "aruco:subpix";
      det.true_corner_rms_px = 0.25;
    }
    for (auto& e : f.estimates)
      e.detector = "aruco:subpix";
  }
  store.append_position(run, p);
  EXPECT_EQ(store.position(run, 0), p);
  EXPECT_EQ(store.run(run).description.primary_detector, "aruco:subpix");
  EXPECT_EQ(RawDb(path).text("PRAGMA integrity_check"), "ok");
}

TEST(StoreSchema, ReadOnlyNeverCreatesAMissingFile) {
  ScratchDir dir;
  const std::string path = dir.file("typo.db");
  try {
    db::store::Store store(path, db::store::StoreOptions{5000, true, true});
    FAIL() << "opened a missing file read-only";
  } catch (const db::store::StoreError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": no such file"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::ifstream(path).good());
}

TEST(StoreSchema, ReadOnlyRefusesAnOlderSchemaItCannotMigrate) {
  ScratchDir dir;
  const std::string path = make_version1_file(dir);
  try {
    db::store::Store store(path, db::store::StoreOptions{5000, true, true});
    FAIL() << "read an old schema read-only";
  } catch (const db::store::SchemaError& e) {
    EXPECT_NE(std::string(e.what()).find("version 1 is older"), std::string::npos) << e.what();
  }
  EXPECT_EQ(RawDb(path).text("PRAGMA user_version"), "1");
}

TEST(StoreSchema, ReadOnlyReadsRunsAndRefusesWrites) {
  ScratchDir dir;
  const std::string path = dir.file("runs.db");
  {
    db::store::Store store(path);
    const std::int64_t run = store.start_run(db_test::make_run_description(2));
    store.append_position(run, db_test::make_position(0));
  }
  db::store::Store reader(path, db::store::StoreOptions{5000, true, true});
  EXPECT_EQ(reader.position(1, 0), db_test::make_position(0));
  EXPECT_THROW(reader.append_position(1, db_test::make_position(1)), db::store::StoreError);
  EXPECT_EQ(reader.completed_position_indices(1), std::vector<std::int64_t>{0});
}
