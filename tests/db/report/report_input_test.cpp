// A report of unusable input fails with ReportInputError naming the file and
// what was expected; and the report's queries use the indexes.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cmath>
#include <fstream>
#include <iostream>

#include "db/report/report.hpp"
#include "db/store/store.hpp"
#include "report_data.hpp"
#include "store_fixture.hpp"
#include "synthetic_run.hpp"

namespace {

using rig_test::SyntheticRunSpec;

SyntheticRunSpec small_spec() {
  SyntheticRunSpec spec;
  spec.positions = 12;
  spec.solvers = {rig_test::paper_like_solvers()[1]};
  return spec;
}

void exec(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  char* error = nullptr;
  const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error);
  const std::string message = error ? error : "";
  sqlite3_free(error);
  sqlite3_close(db);
  ASSERT_EQ(rc, SQLITE_OK) << message;
}

// The message of the ReportInputError that study_run throws ("" if none).
std::string input_error(const std::string& path, db::report::ReportOptions options = {}) {
  try {
    db::report::study_run(path, options);
  } catch (const db::report::ReportInputError& e) {
    return e.what();
  }
  return "";
}

TEST(ReportInput, AMissingFileIsNamedAndNotCreated) {
  db_test::ScratchDir dir;
  const std::string path = dir.file("nope.db");
  const std::string message = input_error(path);
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("no such file"), std::string::npos) << message;
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(ReportInput, AnotherProgramsSqliteFileIsRefusedUnchanged) {
  db_test::ScratchDir dir;
  const std::string path = dir.file("other.db");
  exec(path, "CREATE TABLE notes (text TEXT); INSERT INTO notes VALUES ('hello');");
  const auto before = std::filesystem::file_size(path);
  const std::string message = input_error(path);
  EXPECT_NE(message.find("not a rig run database"), std::string::npos) << message;
  EXPECT_EQ(std::filesystem::file_size(path), before);
}

TEST(ReportInput, AFileThatIsNotSqliteIsRefused) {
  db_test::ScratchDir dir;
  const std::string path = dir.file("text.db");
  std::ofstream(path) << "this is not a database, just text long enough to have a header........"
                         "..........................................................\n";
  const std::string message = input_error(path);
  EXPECT_NE(message.find("not a SQLite database"), std::string::npos) << message;
}

TEST(ReportInput, ANewerSchemaIsRefused) {
  db_test::ScratchDir dir;
  const std::string path = dir.file("newer.db");
  rig_test::write_synthetic_run(path, small_spec());
  exec(path, "PRAGMA user_version = " + std::to_string(db::store::Store::kSchemaVersion + 1));
  const std::string message = input_error(path);
  EXPECT_NE(message.find("newer"), std::string::npos) << message;
}

TEST(ReportInput, ADatabaseWithoutACompletedRunIsRefused) {
  db_test::ScratchDir dir;
  const std::string path = dir.file("running.db");
  SyntheticRunSpec spec = small_spec();
  spec.status = db::store::RunStatus::kRunning;
  const std::int64_t id = rig_test::write_synthetic_run(path, spec).run_id;
  const std::string message = input_error(path);
  EXPECT_NE(message.find("no completed run"), std::string::npos) << message;
  // Named explicitly, a running run is refused too.
  db::report::ReportOptions options;
  options.run_id = id;
  EXPECT_NE(input_error(path, options).find("still running"), std::string::npos);
}

TEST(ReportInput, AnUnknownRunIsNamedWithTheRunsThereAre) {
  db_test::ScratchDir dir;
  const std::string path = dir.file("run.db");
  rig_test::write_synthetic_run(path, small_spec());
  db::report::ReportOptions options;
  options.run_id = 42;
  const std::string message = input_error(path, options);
  EXPECT_NE(message.find("no run 42 (runs: 1)"), std::string::npos) << message;
}

TEST(ReportInput, PicksTheLatestCompletedRunByDefault) {
  db_test::ScratchDir dir;
  const std::string path = dir.file("runs.db");
  rig_test::write_synthetic_run(path, small_spec());
  const std::int64_t second = rig_test::write_synthetic_run(path, small_spec()).run_id;
  SyntheticRunSpec aborted = small_spec();
  aborted.status = db::store::RunStatus::kAborted;
  const std::int64_t third = rig_test::write_synthetic_run(path, aborted).run_id;
  EXPECT_EQ(db::report::study_run(path, {}).run.id, second);
  db::report::ReportOptions options;
  options.run_id = third;
  EXPECT_EQ(db::report::study_run(path, options).run.status, db::store::RunStatus::kAborted);
}

// EXPLAIN QUERY PLAN of every pass over estimates, detections and frames,
// on a file with several runs: only SEARCHes through indexes, no SCAN.
TEST(ReportQueries, UseTheIndexesAndScanNoTable) {
  db_test::ScratchDir dir;
  const std::string path = dir.file("runs.db");
  for (int i = 0; i < 3; ++i)
    rig_test::write_synthetic_run(path, small_spec());
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  // The passes that join start from positions and search every table they
  // reach through an index (2 searches or more); the estimates are one range
  // of row ids (the table's own key) found through their frame_id index.
  struct Pass {
    const char* query;
    int searches;
    const char* through;
  };
  for (const auto& [query, min_searches, through] :
       {Pass{db::report::kEstimateIdsQuery, 1, "INDEX estimates_by_frame_detector_solver"},
        Pass{db::report::kEstimatesQuery, 1, "INTEGER PRIMARY KEY"},
        Pass{db::report::kDetectionsQuery, 2, "INDEX"},
        Pass{db::report::kFramesQuery, 2, "INDEX"}}) {
    sqlite3_stmt* plan = nullptr;
    ASSERT_EQ(sqlite3_prepare_v2(db, (std::string("EXPLAIN QUERY PLAN ") + query).c_str(), -1,
                                 &plan, nullptr),
              SQLITE_OK)
        << sqlite3_errmsg(db);
    sqlite3_bind_int64(plan, 1, 2);
    std::string details;
    int searches = 0;
    while (sqlite3_step(plan) == SQLITE_ROW) {
      const std::string detail = reinterpret_cast<const char*>(sqlite3_column_text(plan, 3));
      details += detail + "\n";
      EXPECT_EQ(detail.rfind("SCAN", 0), std::string::npos) << query << "\n" << detail;
      searches += detail.rfind("SEARCH", 0) == 0 ? 1 : 0;
    }
    sqlite3_finalize(plan);
    EXPECT_GE(searches, min_searches) << details;
    EXPECT_NE(details.find(through), std::string::npos) << details;
    std::cout << details;
  }
  sqlite3_close(db);
}

// The estimates are read in row order and put in plan order: a run whose
// positions were stored last plan index first loads exactly the samples,
// flips and failure counts of the same run stored in plan order.
TEST(ReportInput, RowsStoredOutOfPlanOrderLoadAsInPlanOrder) {
  db_test::ScratchDir dir;
  SyntheticRunSpec spec = small_spec();
  spec.failed_positions = 2;
  const std::string in_order = dir.file("in_order.db"), reversed = dir.file("reversed.db");
  rig_test::write_synthetic_run(in_order, spec);
  spec.stored_in_reverse = true;
  rig_test::write_synthetic_run(reversed, spec);
  const db::report::RunData a = db::report::load_run(in_order, std::nullopt);
  const db::report::RunData b = db::report::load_run(reversed, std::nullopt);
  ASSERT_EQ(a.solvers.size(), b.solvers.size());
  ASSERT_FALSE(a.solvers.empty());
  for (std::size_t i = 0; i < a.solvers.size(); ++i) {
    const auto& sa = a.solvers[i];
    const auto& sb = b.solvers[i];
    EXPECT_EQ(sa.solver, sb.solver);
    EXPECT_EQ(sa.scope, sb.scope);
    EXPECT_EQ(sa.failures_by_termination, sb.failures_by_termination);
    ASSERT_EQ(sa.samples.size(), sb.samples.size()) << sa.solver;
    for (std::size_t k = 0; k < sa.samples.size(); ++k) {
      // Same rows, same arithmetic: equal bits (NaN for absent figures on both).
      EXPECT_EQ(sa.samples[k].position, sb.samples[k].position);
      EXPECT_EQ(sa.samples[k].frame, sb.samples[k].frame);
      EXPECT_EQ(std::isnan(sa.samples[k].distance_m) ? 0.0 : sa.samples[k].distance_m,
                std::isnan(sb.samples[k].distance_m) ? 0.0 : sb.samples[k].distance_m);
      EXPECT_EQ(sa.samples[k].status, sb.samples[k].status);
    }
  }
  ASSERT_EQ(a.flips.size(), b.flips.size());
  for (const auto& [solver, flips] : a.flips) {
    ASSERT_EQ(flips.size(), b.flips.at(solver).size()) << solver;
    for (std::size_t k = 0; k < flips.size(); ++k) {
      EXPECT_EQ(flips[k].position, b.flips.at(solver)[k].position);
      EXPECT_EQ(flips[k].angle_deg, b.flips.at(solver)[k].angle_deg);
    }
  }
}

// Equal bits, NaN equal to NaN: the same rows read through the same
// arithmetic give the same doubles whichever pass read them.
bool same_double(double a, double b) {
  return (std::isnan(a) && std::isnan(b)) || a == b;
}

void expect_same_samples(const db::report::EstimateSample& a, const db::report::EstimateSample& b,
                         const std::string& where) {
  EXPECT_EQ(a.position, b.position) << where;
  EXPECT_EQ(a.frame, b.frame) << where;
  EXPECT_EQ(a.status, b.status) << where;
  for (const auto& [x, y] : {std::pair{a.distance_m, b.distance_m},
                             {a.reprojection_px, b.reprojection_px},
                             {a.generalization_px, b.generalization_px},
                             {a.time_us, b.time_us},
                             {a.ambiguity_ratio, b.ambiguity_ratio},
                             {a.error_x_m, b.error_x_m},
                             {a.error_y_m, b.error_y_m},
                             {a.error_z_m, b.error_z_m},
                             {a.rotation_error_deg, b.rotation_error_deg}})
    EXPECT_TRUE(same_double(x, y)) << where << ": " << x << " vs " << y;
}

// Every estimate, flip and detector of two loads of one run, compared.
void expect_same_run_data(const db::report::RunData& a, const db::report::RunData& b) {
  ASSERT_EQ(a.solvers.size(), b.solvers.size());
  for (std::size_t i = 0; i < a.solvers.size(); ++i) {
    const auto& sa = a.solvers[i];
    const auto& sb = b.solvers[i];
    const std::string where = sa.solver + "/" + sa.scope;
    EXPECT_EQ(sa.solver, sb.solver);
    EXPECT_EQ(sa.scope, sb.scope);
    EXPECT_EQ(sa.failures_by_termination, sb.failures_by_termination) << where;
    ASSERT_EQ(sa.samples.size(), sb.samples.size()) << where;
    for (std::size_t k = 0; k < sa.samples.size(); ++k)
      expect_same_samples(sa.samples[k], sb.samples[k], where + " #" + std::to_string(k));
  }
  ASSERT_EQ(a.flips.size(), b.flips.size());
  for (const auto& [series, flips] : a.flips) {
    ASSERT_EQ(flips.size(), b.flips.at(series).size()) << series;
    for (std::size_t k = 0; k < flips.size(); ++k) {
      EXPECT_EQ(flips[k].position, b.flips.at(series)[k].position) << series;
      EXPECT_EQ(flips[k].angle_deg, b.flips.at(series)[k].angle_deg) << series;
    }
  }
  ASSERT_EQ(a.detectors.size(), b.detectors.size());
  for (std::size_t i = 0; i < a.detectors.size(); ++i) {
    EXPECT_EQ(a.detectors[i].detector, b.detectors[i].detector);
    EXPECT_EQ(a.detectors[i].views_found, b.detectors[i].views_found);
    EXPECT_EQ(a.detectors[i].corners_vs_truth, b.detectors[i].corners_vs_truth);
    EXPECT_EQ(a.detectors[i].misplaced, b.detectors[i].misplaced);
  }
}

// A file of three runs where the middle one was stored out of plan order,
// has failed positions and a second detector's estimates appended after
// every other row (as a re-detection would add them): the run's rows are
// then not one block, and other runs' rows lie around and among them.
std::string awkward_file(db_test::ScratchDir& dir) {
  const std::string path = dir.file("runs.db");
  SyntheticRunSpec spec = small_spec();
  spec.solvers = rig_test::paper_like_solvers();
  rig_test::write_synthetic_run(path, spec);
  spec.failed_positions = 2;
  spec.stored_in_reverse = true;
  rig_test::write_synthetic_run(path, spec);
  spec.stored_in_reverse = false;
  rig_test::write_synthetic_run(path, spec);
  exec(path,
       "INSERT INTO estimates (frame_id, solver, scope, r00, r01, r02, r10, r11, r12, r20, r21, "
       "r22, tx_m, ty_m, tz_m, distance_m, reprojection_error_px, generalization_error_px, "
       "iterations, converged, termination, time_us, ambiguity_ratio, detector) "
       "SELECT e.frame_id, e.solver, e.scope, e.r00, e.r01, e.r02, e.r10, e.r11, e.r12, e.r20, "
       "e.r21, e.r22, e.tx_m, e.ty_m, e.tz_m, e.distance_m + 1e-4, e.reprojection_error_px, "
       "e.generalization_error_px, e.iterations, e.converged, e.termination, e.time_us, "
       "e.ambiguity_ratio, 'aruco' FROM estimates e JOIN frames f ON f.id = e.frame_id "
       "JOIN positions p ON p.id = f.position_id WHERE p.run_id = 2 ORDER BY e.id");
  return path;
}

// The estimates read in two parts on two connections (the default) add up
// to exactly what one pass over them reads: every sample in the same order
// with the same bits, every flip, failure count and detector.
TEST(ReportInput, TwoReadersLoadWhatOneReads) {
  db_test::ScratchDir dir;
  const std::string path = awkward_file(dir);
  const db::report::RunData one = db::report::load_run(path, 2, {}, 1);
  const db::report::RunData two = db::report::load_run(path, 2, {}, 2);
  ASSERT_NE(one.run.description.primary_detector, "aruco");
  bool has_second_detector = false;
  for (const auto& s : one.solvers)
    has_second_detector |= s.solver.find("@aruco") != std::string::npos;
  EXPECT_TRUE(has_second_detector);
  expect_same_run_data(one, two);
}

// A run that changes between the report's snapshot and the second reader's
// (here: its last frame's estimates deleted and its end stamped again, as a
// resume that retakes a position and ends would) is read whole in the
// report's snapshot: the report shows the run as it was when it began.
TEST(ReportInput, ARunChangedWhileBeingReadIsReadAsItWas) {
  db_test::ScratchDir dir;
  const std::string path = awkward_file(dir);
  const db::report::RunData before = db::report::load_run(path, 2, {}, 1);
  const auto change_the_run = [&](db::report::RunData&) {
    exec(path,
         "UPDATE runs SET ended_at = '2099-01-01T00:00:00.000Z' WHERE id = 2; "
         "DELETE FROM estimates WHERE frame_id = (SELECT max(f.id) FROM frames f "
         "JOIN positions p ON p.id = f.position_id WHERE p.run_id = 2)");
  };
  const db::report::RunData read = db::report::load_run(path, 2, change_the_run, 2);
  EXPECT_EQ(read.run.ended_at, before.run.ended_at);
  expect_same_run_data(before, read);
  // The file did change: a load now sees fewer estimates.
  const db::report::RunData after = db::report::load_run(path, 2, {}, 2);
  std::size_t samples_before = 0, samples_after = 0;
  for (const auto& s : before.solvers)
    samples_before += s.samples.size();
  for (const auto& s : after.solvers)
    samples_after += s.samples.size();
  EXPECT_LT(samples_after, samples_before);
}

// A detection with an infinite corner and a visible marker with an infinite
// side (detector or simulator bugs) are left out and counted; the corner
// noise, efficiency and marker-size figures stay finite.
TEST(ReportInput, NonFiniteDetectionsAndSidesAreCountedNotUsed) {
  db_test::ScratchDir dir;
  const std::string path = dir.file("inf_detection.db");
  SyntheticRunSpec spec = small_spec();
  spec.plant_nonfinite_detection = true;
  spec.marker3_lost_beyond_m = 10.0;  // every visible marker is detected
  rig_test::write_synthetic_run(path, spec);
  const db::report::RunStudy st = db::report::study_run(path, {});
  EXPECT_EQ(st.nonfinite_detections, 1u);
  EXPECT_EQ(st.nonfinite_visible_markers, 1u);
  // Plan index 0 (0.12 m) is in the first distance class.
  EXPECT_TRUE(std::isfinite(st.corner_noise[0].sigma_px));
  const db::report::SolverStudy* s = st.find("hybrid_oi", "0");
  ASSERT_NE(s, nullptr);
  EXPECT_TRUE(std::isfinite(s->classes[0].efficiency));
  std::size_t expected = 0, detected = 0;
  for (const db::report::MarkerSizeClass& m : st.marker_sizes) {
    expected += m.expected;
    detected += m.detected;
    EXPECT_TRUE(std::isfinite(m.lower_px) && std::isfinite(m.upper_px));
    if (m.edge_fit_residual_px.count > 0) {
      EXPECT_TRUE(std::isfinite(m.edge_fit_residual_px.mean));
    }
  }
  // Every visible marker x frame but the frames of the infinite side; all
  // of them detected but the infinite detection.
  const std::size_t frames = static_cast<std::size_t>(spec.frames_per_position);
  EXPECT_EQ(expected, 4 * st.frames - frames);
  EXPECT_EQ(detected, expected - 1);
}

}  // namespace

namespace {

// A converged estimate with an infinite value (a solver bug) is counted as a
// failure under its own name; the report's other figures stay finite.
TEST(ReportInput, ANonFiniteConvergedEstimateIsAFailureNotAPoisonedMean) {
  db_test::ScratchDir dir;
  const std::string path = dir.file("inf.db");
  std::int64_t run = 0;
  {
    db::store::Store store(path);
    run = store.start_run(db_test::make_run_description(4));
    for (int i = 0; i < 4; ++i) {
      db::store::PositionRecord p = db_test::make_position(i, 2, 4, 2);
      if (i == 1) p.frames[0].estimates[0].reprojection_error_px = INFINITY;  // solver_0, "0"
      store.append_position(run, p);
    }
    store.finish_run(run, db::store::RunStatus::kCompleted, "");
  }
  const db::report::RunStudy st = db::report::study_run(path, {});
  const db::report::SolverStudy* s = st.find("solver_0", "0");
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->failed, 1u);
  EXPECT_EQ(s->failures_by_termination.at("converged with a non-finite value"), 1u);
  EXPECT_EQ(s->used, 7u);
  EXPECT_TRUE(std::isfinite(s->reprojection_px.mean));
}

}  // namespace
