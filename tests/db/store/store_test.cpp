// Writing and reading runs and positions: every field round-trips, a position
// is written whole or not at all, a plan index is stored once, run statuses
// move only from running, and the resume point is the first missing index.
#include "db/store/store.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <regex>
#include <string>

#include "db/store/sha256.hpp"
#include "store_fixture.hpp"

namespace {

using db_test::make_position;
using db_test::make_run_description;

class StoreTest : public ::testing::Test {
 protected:
  db_test::ScratchDir dir_;
  db::store::Store store_{dir_.file("runs.db")};
};

// started_at/ended_at: ISO 8601 UTC with milliseconds.
const std::regex kIsoTime(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z)");

TEST_F(StoreTest, RoundTripsEveryFieldOfARunWithTheHashesOfItsFiles) {
  const db::store::RunDescription written = make_run_description(42);
  const std::int64_t id = store_.start_run(written);
  const db::store::Run run = store_.run(id);
  EXPECT_EQ(run.id, id);
  EXPECT_EQ(run.status, db::store::RunStatus::kRunning);
  EXPECT_TRUE(run.status_reason.empty());
  EXPECT_TRUE(std::regex_match(run.started_at, kIsoTime)) << run.started_at;
  EXPECT_FALSE(run.ended_at.has_value());
  const db::store::RunDescription& read = run.description;
  EXPECT_EQ(read.config_json, written.config_json);
  EXPECT_EQ(read.plan_json, written.plan_json);
  EXPECT_EQ(read.plan_size, 42);
  EXPECT_EQ(read.software_version, written.software_version);
  EXPECT_EQ(read.library_versions_json, written.library_versions_json);
  EXPECT_EQ(read.host, written.host);
  const std::pair<const db::store::StoredFile*, const db::store::StoredFile*> files[] = {
      {&written.sweep_file, &read.sweep_file},
      {&written.camera_calibration, &read.camera_calibration},
      {&written.target_layout, &read.target_layout},
      {&written.rig_geometry, &read.rig_geometry},
      {&written.bench_profile, &read.bench_profile}};
  for (const auto& [in, out] : files) {
    EXPECT_EQ(out->path, in->path);
    EXPECT_EQ(out->content, in->content) << in->path;  // bytes, NUL and 0xff included
    EXPECT_EQ(out->sha256, db::store::sha256_hex(in->content)) << in->path;
  }
}

// The camera as it identified itself, every field back as written; a
// resumed run records the camera it resumed with instead.
TEST_F(StoreTest, RecordsTheCameraOfARunAndReplacesItOnResume) {
  const std::int64_t id = store_.start_run(make_run_description(10));
  EXPECT_FALSE(store_.run(id).camera.has_value());
  const db::store::RunCamera first{"gige:127.0.0.1", "rig-rig-sim-0001", "rig", "rig-sim",
                                   "0001",           "realism harsh"};
  store_.record_camera(id, first);
  ASSERT_TRUE(store_.run(id).camera.has_value());
  const db::store::RunCamera back = *store_.run(id).camera;
  EXPECT_EQ(back.source, first.source);
  EXPECT_EQ(back.device_id, first.device_id);
  EXPECT_EQ(back.vendor, first.vendor);
  EXPECT_EQ(back.model, first.model);
  EXPECT_EQ(back.serial, first.serial);
  EXPECT_EQ(back.device_version, first.device_version);
  store_.record_camera(id,
                       {"v4l2:/dev/video0", "", "uvcvideo", "HD Webcam", "usb-1", "driver 6.1.0"});
  EXPECT_EQ(store_.run(id).camera->model, "HD Webcam");
  EXPECT_EQ(store_.runs().front().camera->vendor, "uvcvideo");
  EXPECT_THROW(store_.record_camera(id + 1, first), db::store::StoreError);
}

TEST_F(StoreTest, RefusesARunWhoseJsonDoesNotParseNamingTheField) {
  db::store::RunDescription d = make_run_description(1);
  d.config_json = "{\"frames\": ";
  try {
    store_.start_run(d);
    FAIL() << "no StoreError";
  } catch (const db::store::StoreError& e) {
    EXPECT_NE(std::string(e.what()).find("config_json"), std::string::npos) << e.what();
  }
  d = make_run_description(1);
  d.library_versions_json = "[\"opencv\"]";
  EXPECT_THROW(store_.start_run(d), db::store::StoreError);
  EXPECT_TRUE(store_.runs().empty());
}

TEST_F(StoreTest, RoundTripsEveryFieldOfAPosition) {
  const std::int64_t run = store_.start_run(make_run_description(10));
  const db::store::PositionRecord ok = make_position(3);
  db::store::PositionRecord failed = make_position(4, 1, 0, 0);
  failed.status = db::store::PositionStatus::kFailed;
  failed.failure_reason = "camera timeout after 3 retries";
  failed.measured_x_mm.reset();
  failed.measured_y_mm.reset();
  failed.true_distance_m.reset();
  failed.frames.front().camera_timestamp_ns.reset();
  store_.append_position(run, ok);
  store_.append_position(run, failed);
  EXPECT_EQ(store_.position(run, 3), ok);
  EXPECT_EQ(store_.position(run, 4), failed);
}

TEST_F(StoreTest, ListsPositionsByPlanIndexWithoutTheirFrames) {
  const std::int64_t run = store_.start_run(make_run_description(10));
  for (std::int64_t i : {5, 2, 7})
    store_.append_position(run, make_position(i));
  const std::vector<db::store::PositionRecord> positions = store_.positions(run);
  ASSERT_EQ(positions.size(), 3u);
  const std::int64_t expected[] = {2, 5, 7};
  for (std::size_t i = 0; i < 3; ++i) {
    db::store::PositionRecord header = make_position(expected[i]);
    header.frames.clear();
    EXPECT_EQ(positions[i], header);
  }
}

TEST_F(StoreTest, ReadsOneSolversEstimatesWithTheTrueDistanceOfTheirPosition) {
  const std::int64_t run = store_.start_run(make_run_description(10));
  const std::int64_t other = store_.start_run(make_run_description(10));
  for (std::int64_t i : {1, 0})
    store_.append_position(run, make_position(i));
  store_.append_position(other, make_position(0));
  EXPECT_EQ(store_.solvers(run), (std::vector<std::string>{"solver_0", "solver_1", "solver_2"}));
  const std::vector<db::store::EstimateRow> rows = store_.estimates(run, "solver_1");
  // 2 positions x 2 frames x 2 scopes, in plan, frame, append order.
  ASSERT_EQ(rows.size(), 8u);
  std::size_t n = 0;
  for (std::int64_t plan_index : {0, 1}) {
    const db::store::PositionRecord p = make_position(plan_index);
    for (const db::store::FrameRecord& f : p.frames) {
      for (const db::store::EstimateRecord& e : f.estimates) {
        if (e.solver != "solver_1") continue;
        EXPECT_EQ(rows[n].plan_index, plan_index);
        EXPECT_EQ(rows[n].frame_index, f.index);
        EXPECT_EQ(rows[n].true_distance_m, p.true_distance_m);
        EXPECT_EQ(rows[n].estimate, e);
        ++n;
      }
    }
  }
  EXPECT_TRUE(store_.estimates(run, "no_such_solver").empty());
}

TEST_F(StoreTest, RefusesASecondPositionWithTheSamePlanIndexAndKeepsTheFirst) {
  const std::int64_t run = store_.start_run(make_run_description(10));
  const db::store::PositionRecord first = make_position(6);
  db::store::PositionRecord second = make_position(6);
  second.commanded_x_mm += 1.0;
  store_.append_position(run, first);
  EXPECT_THROW(store_.append_position(run, second), db::store::DuplicatePosition);
  EXPECT_EQ(store_.completed_position_indices(run), std::vector<std::int64_t>{6});
  EXPECT_EQ(store_.position(run, 6), first);
}

// rig sweep --resume --retry-failed: a failed position is replaced, with
// everything it held, by its new measurement; a position stored ok, or one
// not stored, is refused and left as it was.
// --resume --retry-failed on a completed run: reopened only when it has a
// failed position to measure again.
TEST_F(StoreTest, ResumesACompletedRunForRetakesOnlyWhenItHasAFailedPosition) {
  const std::int64_t clean = store_.start_run(make_run_description(1));
  store_.append_position(clean, make_position(0));
  store_.finish_run(clean, db::store::RunStatus::kCompleted, "");
  EXPECT_THROW(store_.resume_run(clean, /*completed_with_failed=*/true), db::store::StoreError);
  const std::int64_t with_failed = store_.start_run(make_run_description(1));
  db::store::PositionRecord failed = make_position(0);
  failed.status = db::store::PositionStatus::kFailed;
  failed.failure_reason = "camera: gone";
  store_.append_position(with_failed, failed);
  store_.finish_run(with_failed, db::store::RunStatus::kCompleted, "");
  EXPECT_THROW(store_.resume_run(with_failed), db::store::StoreError);
  store_.resume_run(with_failed, /*completed_with_failed=*/true);
  EXPECT_EQ(store_.run(with_failed).status, db::store::RunStatus::kRunning);
}

TEST_F(StoreTest, RetakesAFailedPositionInPlaceAndRefusesToReplaceAnOkOne) {
  const std::int64_t run = store_.start_run(make_run_description(10));
  db::store::PositionRecord failed = make_position(4);
  failed.status = db::store::PositionStatus::kFailed;
  failed.failure_reason = "camera: no frame within 500 ms";
  store_.append_position(run, failed);
  store_.append_position(run, make_position(5));

  const db::store::PositionRecord retaken = make_position(4, 2, 2, 2);
  store_.retake_failed_position(run, retaken);
  EXPECT_EQ(store_.position(run, 4), retaken);
  EXPECT_EQ(store_.completed_position_indices(run), (std::vector<std::int64_t>{4, 5}));
  // Nothing of the failed record is left behind (its frames went with it).
  EXPECT_EQ(store_.estimates(run, "solver_0").size(),
            make_position(4, 2, 2, 2).frames.size() * 2 + make_position(5).frames.size() * 2)
      << "estimates of solver_0 over positions 4 and 5";

  for (std::int64_t index : {4, 5, 6}) {
    try {
      store_.retake_failed_position(run, make_position(index));
      ADD_FAILURE() << "plan index " << index << " was replaced";
    } catch (const db::store::StoreError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("plan index " + std::to_string(index) +
                             "): the run has no position stored as failed"),
                std::string::npos)
          << message;
    }
  }
  EXPECT_EQ(store_.position(run, 4), retaken);
  EXPECT_EQ(store_.position(run, 5), make_position(5));
  EXPECT_EQ(store_.completed_position_indices(run), (std::vector<std::int64_t>{4, 5}));
}

TEST_F(StoreTest, WritesNothingOfAPositionWhoseLastRowIsRejected) {
  const std::int64_t run = store_.start_run(make_run_description(10));
  db::store::PositionRecord p = make_position(0);
  // Frames, detections and estimates before it are inserted first; the
  // schema's CHECK on rotation (0..3) then fails the transaction.
  p.frames.back().detections.back().rotation = 7;
  try {
    store_.append_position(run, p);
    ADD_FAILURE() << "a rotation of 7 was accepted";
  } catch (const db::store::StoreError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("plan index 0): nothing written"), std::string::npos) << message;
    EXPECT_NE(message.find("rotation"), std::string::npos) << message;
  }
  EXPECT_TRUE(store_.completed_position_indices(run).empty());
  EXPECT_TRUE(store_.estimates(run, "solver_0").empty());
  store_.append_position(run, make_position(0));  // the index is still free
  EXPECT_EQ(store_.position(run, 0), make_position(0));
}

TEST_F(StoreTest, RefusesAPlanIndexOutsideThePlan) {
  const std::int64_t run = store_.start_run(make_run_description(3));
  EXPECT_THROW(store_.append_position(run, make_position(3)), db::store::StoreError);
  EXPECT_THROW(store_.append_position(run, make_position(-1)), db::store::StoreError);
  EXPECT_THROW(store_.append_position(run + 1, make_position(0)), db::store::StoreError);
}

TEST_F(StoreTest, ResumesFromTheFirstPlanIndexNotStored) {
  const std::int64_t run = store_.start_run(make_run_description(5));
  EXPECT_EQ(store_.first_incomplete_position(run), 0);
  for (std::int64_t i : {0, 1, 2, 4})
    store_.append_position(run, make_position(i, 1, 1, 1));
  EXPECT_EQ(store_.completed_position_indices(run), (std::vector<std::int64_t>{0, 1, 2, 4}));
  EXPECT_EQ(store_.first_incomplete_position(run), 3);
  store_.append_position(run, make_position(3, 1, 1, 1));
  EXPECT_EQ(store_.first_incomplete_position(run), std::nullopt);
}

TEST_F(StoreTest, FinishesARunOnceWithItsStatusReasonAndEndTime) {
  const std::int64_t run = store_.start_run(make_run_description(5));
  store_.finish_run(run, db::store::RunStatus::kAborted, "SIGINT");
  const db::store::Run aborted = store_.run(run);
  EXPECT_EQ(aborted.status, db::store::RunStatus::kAborted);
  EXPECT_EQ(aborted.status_reason, "SIGINT");
  ASSERT_TRUE(aborted.ended_at.has_value());
  EXPECT_TRUE(std::regex_match(*aborted.ended_at, kIsoTime)) << *aborted.ended_at;
  EXPECT_THROW(store_.finish_run(run, db::store::RunStatus::kCompleted, ""), db::store::StoreError);
  EXPECT_THROW(store_.append_position(run, make_position(0)), db::store::StoreError);
}

TEST_F(StoreTest, RequiresAReasonToAbortOrFailAndRefusesRunningAsAnEnd) {
  const std::int64_t run = store_.start_run(make_run_description(5));
  EXPECT_THROW(store_.finish_run(run, db::store::RunStatus::kFailed, ""), db::store::StoreError);
  EXPECT_THROW(store_.finish_run(run, db::store::RunStatus::kRunning, "x"), db::store::StoreError);
  EXPECT_EQ(store_.run(run).status, db::store::RunStatus::kRunning);
}

TEST_F(StoreTest, ResumesAnAbortedRunButNotACompletedOne) {
  const std::int64_t run = store_.start_run(make_run_description(5));
  store_.append_position(run, make_position(0, 1, 1, 1));
  store_.finish_run(run, db::store::RunStatus::kAborted, "SIGTERM");
  store_.resume_run(run);
  const db::store::Run resumed = store_.run(run);
  EXPECT_EQ(resumed.status, db::store::RunStatus::kRunning);
  EXPECT_FALSE(resumed.ended_at.has_value());
  EXPECT_TRUE(resumed.status_reason.empty());
  store_.append_position(run, make_position(1, 1, 1, 1));
  store_.finish_run(run, db::store::RunStatus::kCompleted, "");
  EXPECT_THROW(store_.resume_run(run), db::store::StoreError);
}

TEST(SqliteLibraryVersion, IsTheVersionOfTheLinkedLibrary) {
  // The header's version and the linked library's agree on Debian 12; both
  // are "3.x.y".
  EXPECT_EQ(db::store::sqlite_library_version(), SQLITE_VERSION);
}

TEST_F(StoreTest, ListsRunsOldestFirst) {
  const std::int64_t a = store_.start_run(make_run_description(1));
  const std::int64_t b = store_.start_run(make_run_description(2));
  const std::vector<db::store::Run> runs = store_.runs();
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0].id, a);
  EXPECT_EQ(runs[1].id, b);
  EXPECT_EQ(runs[1].description.plan_size, 2);
  EXPECT_THROW(store_.run(b + 1), db::store::StoreError);
}

TEST_F(StoreTest, ASecondStoreOnTheFileSeesEachCommittedPosition) {
  const std::int64_t run = store_.start_run(make_run_description(5));
  db::store::Store reader(dir_.file("runs.db"));
  EXPECT_EQ(reader.first_incomplete_position(run), 0);
  store_.append_position(run, make_position(0));
  EXPECT_EQ(reader.first_incomplete_position(run), 1);
  EXPECT_EQ(reader.position(run, 0), make_position(0));
}

TEST_F(StoreTest, FailsAnAppendWhileAnotherConnectionHoldsTheWriteLock) {
  const std::int64_t run = store_.start_run(make_run_description(5));
  db::store::StoreOptions impatient;
  impatient.busy_timeout_ms = 0;  // fail at once instead of waiting for the lock
  db::store::Store second(dir_.file("runs.db"), impatient);
  {
    // store_ takes the write lock inside append_position; hold it from here
    // with a raw connection instead.
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(dir_.file("runs.db").c_str(), &raw), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(raw, "BEGIN IMMEDIATE", nullptr, nullptr, nullptr), SQLITE_OK);
    try {
      second.append_position(run, make_position(0));
      ADD_FAILURE() << "append succeeded without the write lock";
    } catch (const db::store::StoreError& e) {
      EXPECT_NE(std::string(e.what()).find("locked"), std::string::npos) << e.what();
    }
    sqlite3_exec(raw, "ROLLBACK", nullptr, nullptr, nullptr);
    sqlite3_close(raw);
  }
  second.append_position(run, make_position(0));  // the lock is free again
  EXPECT_EQ(store_.completed_position_indices(run), std::vector<std::int64_t>{0});
}

TEST_F(StoreTest, RecordsARunsEventsInOrderWithTheirPositions) {
  const std::int64_t run = store_.start_run(make_run_description(5));
  const std::int64_t other = store_.start_run(make_run_description(5));
  store_.record_event(run, "alarm", "following error (code 2)", 3);
  store_.record_event(other, "pause", "asked by rig ctl");
  store_.record_event(run, "resume", "asked by rig ctl");
  const std::vector<db::store::RunEvent> events = store_.events(run);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].kind, "alarm");
  EXPECT_EQ(events[0].plan_index, 3);
  EXPECT_EQ(events[0].message, "following error (code 2)");
  EXPECT_EQ(events[1].kind, "resume");
  EXPECT_FALSE(events[1].plan_index.has_value());
  EXPECT_LE(events[0].at, events[1].at);  // ISO 8601 sorts as time
  EXPECT_EQ(store_.events(other).size(), 1u);
  EXPECT_THROW(store_.record_event(run, "", "no kind"), db::store::StoreError);
  EXPECT_THROW(store_.record_event(99, "alarm", "no such run"), db::store::StoreError);
}

TEST(StoreTiming, RecordsTheStoresOwnTimeAsTheLastStageWhenAsked) {
  db_test::ScratchDir dir;
  db::store::StoreOptions options;
  options.record_store_time = true;
  db::store::Store store(dir.file("timed.db"), options);
  const std::int64_t run = store.start_run(make_run_description(1));
  const db::store::PositionRecord written = make_position(0);
  store.append_position(run, written);
  const db::store::PositionRecord back = store.position(run, 0);
  ASSERT_EQ(back.stage_times.size(), written.stage_times.size() + 1);
  EXPECT_EQ(back.stage_times.back().stage, "store");
  // Positive (it did work) and below a second (a few dozen inserts of one position).
  EXPECT_GT(back.stage_times.back().seconds, 0.0);
  EXPECT_LT(back.stage_times.back().seconds, 1.0);
}

}  // namespace
