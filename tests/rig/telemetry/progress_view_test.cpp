// ProgressView: ETA arithmetic checked by hand, and the text it renders.
#include "rig/telemetry/progress_view.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>
#include <vector>

namespace {

using nlohmann::json;

json run_start(int plan_size) {
  return {{"type", "run_start"},
          {"run_id", 7},
          {"database", "/tmp/run.db"},
          {"plan_size", plan_size},
          {"first_index", 0},
          {"resumed", false},
          {"solvers", {"analytic", "lm"}},
          {"frames_per_position", 3},
          {"sweep_file", "config/sweeps/ci.toml"}};
}

json estimate(const std::string& solver, const std::string& scope, double error_m,
              bool converged = true) {
  return {{"solver", solver},
          {"scope", scope},
          {"distance_m", 0.61 + error_m},
          {"distance_error_m", error_m},
          {"reprojection_error_px", 0.25},
          {"generalization_error_px", nullptr},
          {"converged", converged}};
}

json position(int completed, double elapsed_s, int plan_size = 10) {
  return {{"type", "position"},
          {"run_id", 7},
          {"plan_index", completed - 1},
          {"completed", completed},
          {"plan_size", plan_size},
          {"status", "ok"},
          {"commanded", {{"x_mm", 100.0}, {"y_mm", 50.0}}},
          {"measured", {{"x_mm", 100.002}, {"y_mm", 49.999}}},
          {"true_distance_m", 0.61},
          {"markers_detected", 4},
          {"estimates",
           {estimate("analytic", "0", 0.004), estimate("lm", "0", -0.0015),
            estimate("lm", "target", 0.0008)}},
          {"elapsed_s", elapsed_s}};
}

json state(const std::string& s) {
  return {{"type", "state"}, {"run_id", 7}, {"state", s}};
}

TEST(FormatDuration, RoundsAndPicksUnits) {
  EXPECT_EQ(rig::telemetry::format_duration(0), "0s");
  EXPECT_EQ(rig::telemetry::format_duration(59.4), "59s");
  EXPECT_EQ(rig::telemetry::format_duration(59.6), "1m00s");
  EXPECT_EQ(rig::telemetry::format_duration(83), "1m23s");
  EXPECT_EQ(rig::telemetry::format_duration(7500), "2h05m");  // 2 h 5 min exactly
  EXPECT_EQ(rig::telemetry::format_duration(-1), "--");
  EXPECT_EQ(rig::telemetry::format_duration(std::nan("")), "--");
}

TEST(ProgressView, EtaIsMeanSecondsPerPositionTimesPositionsLeft) {
  rig::telemetry::ProgressView view;
  view.update(run_start(10));
  EXPECT_FALSE(view.eta_s());
  // 2 s per position, three times: mean 2 s, 7 left -> 14 s.
  view.update(position(1, 2.0));
  view.update(position(2, 4.0));
  view.update(position(3, 6.0));
  ASSERT_TRUE(view.seconds_per_position());
  EXPECT_DOUBLE_EQ(*view.seconds_per_position(), 2.0);
  EXPECT_DOUBLE_EQ(*view.eta_s(), 14.0);
}

TEST(ProgressView, EtaWeighsTheNewestIntervalBySmoothing) {
  rig::telemetry::ProgressView view(0.2);
  view.update(run_start(10));
  view.update(position(1, 2.0));  // sample 2 -> mean 2
  view.update(position(2, 6.0));  // sample 4 -> 2 + 0.2 (4 - 2) = 2.4
  EXPECT_DOUBLE_EQ(*view.seconds_per_position(), 2.4);
  EXPECT_DOUBLE_EQ(*view.eta_s(), 2.4 * 8);  // 19.2 s
}

TEST(ProgressView, AnIntervalWithAPauseIsLeftOut) {
  rig::telemetry::ProgressView view;
  view.update(run_start(10));
  view.update(position(1, 2.0));
  view.update(position(2, 4.0));
  view.update(state("paused"));
  EXPECT_EQ(view.state(), "paused");
  view.update(state("running"));
  view.update(position(3, 100.0));  // 96 s, most of it paused: not a sample
  EXPECT_DOUBLE_EQ(*view.seconds_per_position(), 2.0);
  view.update(position(4, 102.0));  // 2 s again
  EXPECT_DOUBLE_EQ(*view.seconds_per_position(), 2.0);
  EXPECT_DOUBLE_EQ(*view.eta_s(), 12.0);
}

TEST(ProgressView, AFaultThatPausesAlsoLeavesItsIntervalOut) {
  rig::telemetry::ProgressView view;
  view.update(run_start(10));
  view.update(position(1, 2.0));
  view.update({{"type", "fault"}, {"kind", "alarm"}, {"action", "pause"}, {"plan_index", 1}});
  EXPECT_EQ(view.state(), "paused");
  view.update(position(2, 50.0));
  EXPECT_EQ(view.state(), "running");
  EXPECT_DOUBLE_EQ(*view.seconds_per_position(), 2.0);
}

TEST(ProgressView, MissedMessagesShareTheirIntervalAmongThePositionsStored) {
  rig::telemetry::ProgressView view;
  view.update(run_start(10));
  view.update(position(1, 2.0));
  view.update(position(4, 8.0));  // 6 s for 3 positions: 2 s each
  EXPECT_DOUBLE_EQ(*view.seconds_per_position(), 2.0);
  EXPECT_DOUBLE_EQ(*view.eta_s(), 12.0);
}

TEST(ProgressView, JoiningMidRunStartsFromTheFirstPositionSeen) {
  rig::telemetry::ProgressView view;
  view.update(position(40, 80.0, 100));  // no run_start: only a reference
  EXPECT_FALSE(view.seconds_per_position());
  EXPECT_EQ(view.completed(), 40);
  EXPECT_EQ(view.plan_size(), 100);
  view.update(position(41, 83.0, 100));
  EXPECT_DOUBLE_EQ(*view.eta_s(), 3.0 * 59);
}

TEST(ProgressView, AResumedRunsFirstPositionCountsAsOne) {
  rig::telemetry::ProgressView view;
  json start = run_start(100);
  start["resumed"] = true;
  view.update(start);
  view.update(position(51, 1.5, 100));  // 50 stored before; this session's first took 1.5 s
  EXPECT_DOUBLE_EQ(*view.seconds_per_position(), 1.5);
  EXPECT_DOUBLE_EQ(*view.eta_s(), 1.5 * 49);
}

TEST(ProgressView, EtaIsZeroOnceThePlanIsDone) {
  rig::telemetry::ProgressView view;
  view.update(run_start(2));
  view.update(position(1, 1.0, 2));
  view.update(position(2, 2.0, 2));
  EXPECT_DOUBLE_EQ(*view.eta_s(), 0.0);
}

TEST(ProgressView, RunStopSetsStateAndFailedCount) {
  rig::telemetry::ProgressView view;
  view.update(run_start(10));
  json failed = position(1, 2.0);
  failed["status"] = "failed";
  view.update(failed);
  EXPECT_EQ(view.failed(), 1);
  view.update({{"type", "run_stop"},
               {"run_id", 7},
               {"status", "aborted"},
               {"reason", "operator"},
               {"positions_ok", 0},
               {"positions_failed", 3},
               {"plan_size", 10},
               {"elapsed_s", 80.2}});
  EXPECT_TRUE(view.stopped());
  EXPECT_EQ(view.state(), "aborted");
  EXPECT_EQ(view.failed(), 3);
}

TEST(ProgressView, ProgressLineShowsPercentCountEtaAndState) {
  rig::telemetry::ProgressView view;
  view.update(run_start(10));
  view.update(position(1, 2.0));
  view.update(position(2, 4.0));
  view.update(position(3, 6.0));
  const std::string line = view.progress_line(80);
  EXPECT_EQ(line.size(), 80u);
  // 30% of a bar of 80 - 2 brackets - suffix characters.
  const std::string suffix = "  30.0%  3/10  ETA 14s  failed 0  running";
  ASSERT_GE(line.size(), suffix.size());
  EXPECT_EQ(line.substr(line.size() - suffix.size()), suffix);
  const int bar = 80 - 2 - static_cast<int>(suffix.size());
  EXPECT_EQ(line.substr(0, 1 + bar * 3 / 10), "[" + std::string(bar * 3 / 10, '#'));
  EXPECT_EQ(line[1 + bar * 3 / 10], '-');
}

TEST(ProgressView, ProgressLineDropsTheBarWhenNarrowAndNeverExceedsTheWidth) {
  rig::telemetry::ProgressView view;
  view.update(run_start(10));
  view.update(position(3, 6.0));
  for (int width : {20, 30, 45, 52, 60, 120}) {
    const std::string line = view.progress_line(width);
    EXPECT_LE(static_cast<int>(line.size()), width) << line;
  }
  EXPECT_EQ(view.progress_line(40).find('['), std::string::npos);
}

TEST(ProgressView, LogLineNamesPositionPlaceTruthAndBestSolver) {
  rig::telemetry::ProgressView view;
  EXPECT_EQ(view.log_line(position(13, 12.3, 201)),
            "position 12 (13/201) ok: x 100.002 y 49.999 mm, true 0.6100 m, 4 markers, "
            "best lm (target) +0.80 mm, 12.3 s");
}

TEST(ProgressView, LogLineOfAFailedPositionGivesTheReason) {
  rig::telemetry::ProgressView view;
  json p = position(13, 12.3, 201);
  p["status"] = "failed";
  p["failure_reason"] = "no marker detected";
  EXPECT_EQ(view.log_line(p),
            "position 12 (13/201) FAILED: no marker detected; x 100.002 y 49.999 mm");
}

TEST(ProgressView, LogLineSkipsEstimatesThatDidNotConverge) {
  rig::telemetry::ProgressView view;
  json p = position(1, 1.0);
  p["estimates"] =
      json::array({estimate("lm", "target", 0.0001, false), estimate("analytic", "0", 0.002)});
  EXPECT_NE(view.log_line(p).find("best analytic (marker 0) +2.00 mm"), std::string::npos);
  p["estimates"] = json::array({estimate("lm", "target", 0.0001, false)});
  ASSERT_TRUE(p["estimates"].is_array()) << "else the line below would hold vacuously";
  EXPECT_NE(view.log_line(p).find("no converged estimate"), std::string::npos);
}

TEST(ProgressView, SolverTableKeepsTheLatestErrorPerSolverAndScopeInRunOrder) {
  rig::telemetry::ProgressView view;
  view.update(run_start(10));
  view.update(position(1, 1.0));
  json later = position(2, 2.0);
  // json::array, not a braced single value: clang (unlike gcc) reads
  // `= {estimate(...)}` as a copy of that one object, so the position would
  // carry no estimates array and the table would keep position 0.
  later["estimates"] = json::array({estimate("lm", "target", -0.0021)});
  ASSERT_TRUE(later["estimates"].is_array());
  view.update(later);
  const std::string table = view.solver_table();
  EXPECT_NE(table.find("latest estimates (position 1)"), std::string::npos) << table;
  // Columns aligned to the longest name ("analytic", 8 characters).
  const auto analytic = table.find("analytic marker 0");
  const auto lm_marker = table.find("lm       marker 0");
  const auto lm_target = table.find("lm       target");
  ASSERT_NE(analytic, std::string::npos) << table;
  ASSERT_NE(lm_marker, std::string::npos) << table;
  ASSERT_NE(lm_target, std::string::npos) << table;
  EXPECT_LT(analytic, lm_marker);
  EXPECT_LT(lm_marker, lm_target);
  // lm target row updated by the later position; the others kept from the first.
  EXPECT_NE(table.find("-2.10 mm", lm_target), std::string::npos) << table;
  EXPECT_NE(table.find("+4.00 mm", analytic), std::string::npos) << table;
  EXPECT_NE(table.find("- px"), std::string::npos) << "null generalization error shows as -";
}

TEST(ProgressView, DescribesEveryMessageType) {
  rig::telemetry::ProgressView view;
  EXPECT_EQ(view.describe(run_start(201)),
            "run 7 started: 201 positions from index 0, solvers analytic, lm, 3 frames per "
            "position, database /tmp/run.db");
  EXPECT_EQ(view.describe({{"type", "fault"},
                           {"plan_index", 12},
                           {"kind", "alarm"},
                           {"message", "drive alarm 0x21"},
                           {"action", "pause"}}),
            "fault at position 12: alarm: drive alarm 0x21 (action: pause)");
  EXPECT_EQ(view.describe(state("paused")), "run 7 paused");
  EXPECT_EQ(view.describe({{"type", "run_stop"},
                           {"run_id", 7},
                           {"status", "completed"},
                           {"reason", ""},
                           {"positions_ok", 200},
                           {"positions_failed", 1},
                           {"plan_size", 201},
                           {"elapsed_s", 80.2}}),
            "run 7 completed: 200 ok, 1 failed of 201 positions in 1m20s");
}

TEST(ProgressView, SurvivesMissingAndMistypedFields) {
  rig::telemetry::ProgressView view;
  view.update(json{{"type", "position"}, {"completed", "many"}, {"estimates", 3}});
  view.update(json::array());
  view.update(json{{"type", "run_stop"}});
  EXPECT_EQ(view.log_line(json::object()),
            "position - (-/-) -: x - y - mm, true - m, - markers, "
            "no converged estimate, - s");
  EXPECT_FALSE(view.dashboard(80).empty());
}

TEST(ProgressView, DashboardShowsRunProgressSolversAndTheLastFault) {
  rig::telemetry::ProgressView view;
  EXPECT_EQ(view.dashboard(80).rfind("waiting for telemetry\n", 0), 0u);
  view.update(run_start(10));
  view.update(position(1, 2.0));
  view.update({{"type", "fault"},
               {"plan_index", 1},
               {"kind", "link"},
               {"message", "modbus timeout"},
               {"action", "retry"}});
  const std::string screen = view.dashboard(80);
  EXPECT_EQ(screen.rfind("run 7  config/sweeps/ci.toml  ->  /tmp/run.db\n", 0), 0u) << screen;
  EXPECT_NE(screen.find(view.progress_line(80) + "\n"), std::string::npos) << screen;
  EXPECT_NE(screen.find(view.solver_table()), std::string::npos) << screen;
  EXPECT_NE(screen.find("last fault: fault at position 1: link: modbus timeout (action: retry)"),
            std::string::npos)
      << screen;
}

// Ten solvers on two scopes with long names: 20 rows do not fit 24 lines
// with the run, progress, faults and last message, so the screen keeps the
// progress line and summarises the rows that do not fit.
TEST(ProgressView, DashboardFitsEightyByTwentyFourWithTenSolvers) {
  rig::telemetry::ProgressView view;
  json start = run_start(50);
  start["solvers"] = json::array();
  json p = position(3, 6.0, 50);
  p["estimates"] = json::array();
  for (int i = 0; i < 10; ++i) {
    const std::string name = "solver_with_a_long_name_" + std::to_string(i);
    start["solvers"].push_back(name);
    p["estimates"].push_back(estimate(name, "0", 0.0001 * i));
    json target = estimate(name, "target", 0.000002);
    if (i == 0) target["applicable"] = false;
    p["estimates"].push_back(target);
  }
  view.update(start);
  view.update(position(1, 2.0, 50));
  view.update(position(2, 4.0, 50));
  view.update(p);
  const std::string screen = view.dashboard(80, 24);
  std::istringstream lines(screen);
  std::vector<std::string> rows;
  for (std::string l; std::getline(lines, l);)
    rows.push_back(l);
  // At most 23 lines: the 24th would scroll the first off the terminal.
  EXPECT_LE(rows.size(), 23u) << screen;
  for (const std::string& r : rows) {  // columns: UTF-8 code points (µ is 2 bytes, 1 column)
    const auto columns = std::count_if(
        r.begin(), r.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; });
    EXPECT_LE(columns, 80) << r;
  }
  EXPECT_EQ(rows[1], view.progress_line(80));
  EXPECT_NE(rows[1].find("ETA"), std::string::npos);
  EXPECT_NE(screen.find(" more rows: "), std::string::npos) << screen;
  // 0.0001 m is 0.10 mm; 2 µm would round to +0.00 mm, so it shows in µm.
  EXPECT_NE(screen.find("+0.10 mm"), std::string::npos) << screen;
  const std::string table = view.solver_table();
  EXPECT_NE(table.find("+2.0 µm"), std::string::npos) << table;
  EXPECT_NE(table.find("solver_with_a_long_name_0 target" + std::string(12, ' ') + "n/a" +
                       std::string(7, ' ') + "n/a" + std::string(8, ' ') + "n/a  n/a"),
            std::string::npos)
      << table;
  // Every row's scope column starts at the same place.
  const auto first = table.find("solver_with_a_long_name_0 marker 0");
  EXPECT_NE(first, std::string::npos) << table;
}

TEST(ProgressView, AMonitorThatJoinsLateShowsTheRunAndDatabase) {
  rig::telemetry::ProgressView view;
  json p = position(5, 10.0, 20);
  p["database"] = "runs/ci.db";
  view.update(p);
  const std::string screen = view.dashboard(80, 24);
  EXPECT_EQ(screen.rfind("run 7 (joined after its start)  ->  runs/ci.db\n", 0), 0u) << screen;
}

TEST(DescribeStatus, IsOneLineForPeople) {
  EXPECT_EQ(rig::telemetry::describe_status({{"state", "running"},
                                             {"run_id", 7},
                                             {"completed", 45},
                                             {"plan_size", 200},
                                             {"current_index", 45},
                                             {"eta_s", 83.0}}),
            "state running, run 7: 45 of 200 positions stored (22.5 %), at plan index 45, ETA "
            "1m23s");
  EXPECT_EQ(rig::telemetry::describe_status({{"state", "paused"}}),
            "state paused, run -: - of - positions stored, at plan index -, ETA --");
}

TEST(ProgressPrinter, WithoutATerminalPrintsOneLinePerMessage) {
  std::ostringstream out;
  rig::telemetry::ProgressPrinter printer(out, false, 80);
  printer.update(run_start(2));
  printer.update(position(1, 1.0, 2));
  printer.update({{"type", "run_stop"}, {"run_id", 7}, {"status", "completed"}});
  const std::string text = out.str();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 3);
  EXPECT_EQ(text.find('\r'), std::string::npos);
  EXPECT_EQ(text.find('\x1b'), std::string::npos);
}

TEST(ProgressPrinter, OnATerminalRedrawsOneBarAndEndsWithANewline) {
  std::ostringstream out;
  rig::telemetry::ProgressPrinter printer(out, true, 60);
  printer.update(run_start(2));
  printer.update(position(1, 1.0, 2));
  printer.update(position(2, 2.0, 2));
  printer.update({{"type", "run_stop"}, {"run_id", 7}, {"status", "completed"}});
  const std::string text = out.str();
  // Lines: run start and run stop; positions only redraw the bar in place.
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 2) << text;
  EXPECT_NE(text.find("100.0%  2/2"), std::string::npos) << text;
  EXPECT_EQ(text.back(), '\n');
}

}  // namespace
