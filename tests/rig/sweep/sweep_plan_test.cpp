// rig::sweep::SweepPlan: grid order, end inclusion, CSV parsing and its errors, the
// paper's preset, the JSON round trip.
#include "rig/sweep/sweep_plan.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "vision/rig_geometry.hpp"

namespace {

using rig::sweep::PlanError;
using rig::sweep::PlanPosition;
using rig::sweep::SweepPlan;

std::vector<std::pair<double, double>> xy(const SweepPlan& plan) {
  std::vector<std::pair<double, double>> out;
  for (const PlanPosition& p : plan.positions())
    out.emplace_back(p.x_mm, p.y_mm);
  return out;
}

// The message of the PlanError that `f` throws ("" if it throws none).
template <typename F>
std::string plan_error(F f) {
  try {
    f();
  } catch (const PlanError& e) {
    return e.what();
  }
  return "";
}

// A file under the test's temporary folder with the given content.
std::string write_file(const std::string& name, const std::string& content) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("sweep_plan_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path) << content;
  return path;
}

TEST(SweepPlanGrid, SerpentineReversesEveryOtherRow) {
  // Hand-checked: x 0, 10, 20; y 0, 5, 10.
  const SweepPlan plan = SweepPlan::grid({0, 20, 10, 0, 10, 5, true});
  const std::vector<std::pair<double, double>> expected = {
      {0, 0}, {10, 0}, {20, 0}, {20, 5}, {10, 5}, {0, 5}, {0, 10}, {10, 10}, {20, 10}};
  EXPECT_EQ(xy(plan), expected);
  EXPECT_EQ(plan.size(), 9u);
}

TEST(SweepPlanGrid, RowByRowKeepsEveryRowAscending) {
  const SweepPlan plan = SweepPlan::grid({0, 20, 10, 0, 5, 5, false});
  const std::vector<std::pair<double, double>> expected = {{0, 0}, {10, 0}, {20, 0},
                                                           {0, 5}, {10, 5}, {20, 5}};
  EXPECT_EQ(xy(plan), expected);
}

TEST(SweepPlanGrid, LastStepIsShorterSoTheMaximumIsVisitedExactly) {
  // 0..25 step 10: 0, 10, 20, then 25 (a 5 mm step), not 30.
  const SweepPlan plan = SweepPlan::grid({0, 25, 10, 7, 7, 1, true});
  const std::vector<std::pair<double, double>> expected = {{0, 7}, {10, 7}, {20, 7}, {25, 7}};
  EXPECT_EQ(xy(plan), expected);
}

TEST(SweepPlanGrid, AStepThatDividesTheRangeUpToRoundingAddsNoExtraPosition) {
  // 0.1 is not exact in binary: 10 steps of 0.1 do not sum to exactly 1.0.
  // The grid must have 11 values, the last exactly 1.0.
  const SweepPlan plan = SweepPlan::grid({0, 1.0, 0.1, 0, 0, 1, true});
  ASSERT_EQ(plan.size(), 11u);
  EXPECT_EQ(plan.positions().back().x_mm, 1.0);
  const SweepPlan ci = SweepPlan::grid({0, 900, 12.5, 140, 160, 10, true});
  EXPECT_EQ(ci.size(), 73u * 3u);
}

TEST(SweepPlanGrid, DescriptionNamesRangesStepsOrderAndCount) {
  const SweepPlan plan = SweepPlan::grid({0, 900, 50, 100, 200, 50, true});
  EXPECT_EQ(plan.size(), 57u);  // 19 x 3
  EXPECT_EQ(plan.description(),
            "grid x 0..900 step 50 mm, y 100..200 step 50 mm, serpentine (57 positions)");
}

TEST(SweepPlanGrid, RefusesBadRangesAndStepsNamingTheValue) {
  EXPECT_EQ(plan_error([] {
              SweepPlan::grid({0, 900, -5, 0, 0, 1, true});
            }),
            "grid: x_step_mm = -5: expected a finite number > 0");
  EXPECT_EQ(plan_error([] {
              SweepPlan::grid({0, 900, 5, 10, 0, 1, true});
            }),
            "grid: y_max_mm = 0: expected >= y_min_mm (10)");
  EXPECT_EQ(plan_error([] {
              SweepPlan::grid({NAN, 900, 5, 0, 0, 1, true});
            }),
            "grid: x_min_mm = nan: expected a finite number");
  // A step typed in metres: 9e8 positions must be refused before they are made.
  EXPECT_NE(plan_error([] {
              SweepPlan::grid({0, 900, 1e-6, 0, 0, 1, true});
            }).find("expected a step giving at most 1000000 positions"),
            std::string::npos);
}

TEST(SweepPlanCsv, ReadsPositionsSkippingCommentsAndBlankLines) {
  const std::string path = write_file("good.csv",
                                      "# a plan\n"
                                      "\n"
                                      " x_mm , y_mm \r\n"
                                      "0,150\n"
                                      "  # comment line\n"
                                      "12.5, 149.75  # trailing comment\n"
                                      "\n"
                                      "-0.5,3e1\n");
  const SweepPlan plan = SweepPlan::from_csv(path);
  const std::vector<std::pair<double, double>> expected = {{0, 150}, {12.5, 149.75}, {-0.5, 30}};
  EXPECT_EQ(xy(plan), expected);
  EXPECT_EQ(plan.description(), "csv " + path + " (3 positions)");
}

TEST(SweepPlanCsv, AcceptsTheByteOrderMarkOfASpreadsheetExport) {
  const std::string path = write_file("bom.csv", "\xEF\xBB\xBFx_mm,y_mm\r\n1,2\r\n");
  const std::vector<std::pair<double, double>> expected = {{1, 2}};
  EXPECT_EQ(xy(SweepPlan::from_csv(path)), expected);
}

TEST(SweepPlanCsv, ErrorsNameFileLineValueAndExpectation) {
  struct Case {
    const char* name;
    const char* content;
    std::string expected;  // after "PATH"
  };
  const std::vector<Case> cases = {
      {"no_header.csv", "# c\n0,150\n", ":2: \"0,150\": expected the header \"x_mm,y_mm\""},
      {"bad_x.csv", "x_mm,y_mm\n0,1\nabc,150\n",
       ":3: x_mm = \"abc\": expected a finite number (mm)"},
      {"bad_y.csv", "x_mm,y_mm\n\n5,1.5.2\n",
       ":3: y_mm = \"1.5.2\": expected a finite number (mm)"},
      {"three.csv", "x_mm,y_mm\n1,2,3\n", ":2: \"1,2,3\": expected two fields \"X,Y\" (mm)"},
      {"one.csv", "x_mm,y_mm\n1\n", ":2: \"1\": expected two fields \"X,Y\" (mm)"},
      {"empty_y.csv", "x_mm,y_mm\n1,\n", ":2: y_mm = \"\": expected a finite number (mm)"},
      {"inf.csv", "x_mm,y_mm\ninf,1\n", ":2: x_mm = \"inf\": expected a finite number (mm)"},
      {"no_rows.csv", "x_mm,y_mm\n# nothing\n",
       ": no positions after the header: expected at least one \"X,Y\" line"},
      {"empty.csv", "", ": empty plan: expected the header \"x_mm,y_mm\""},
  };
  for (const Case& c : cases) {
    const std::string path = write_file(c.name, c.content);
    EXPECT_EQ(plan_error([&] { SweepPlan::from_csv(path); }), path + c.expected) << c.name;
  }
  EXPECT_EQ(plan_error([] { SweepPlan::from_csv("/nonexistent/plan.csv"); }),
            "/nonexistent/plan.csv: cannot open the plan file (expected a readable CSV file)");
}

TEST(SweepPlanPaper, Has1939PositionsIn7SerpentineRowsCoveringTheBox) {
  const SweepPlan plan = SweepPlan::paper(0, 900, 135, 165);
  ASSERT_EQ(plan.size(), 1939u);
  const auto& p = plan.positions();
  EXPECT_EQ(p.front().x_mm, 0);
  EXPECT_EQ(p.front().y_mm, 135);
  EXPECT_EQ(p[276].x_mm, 900);  // end of row 0
  EXPECT_EQ(p[277].x_mm, 900);  // row 1 runs back
  EXPECT_EQ(p[277].y_mm, 140);
  EXPECT_EQ(p.back().x_mm, 900);  // row 6 runs forward again
  EXPECT_EQ(p.back().y_mm, 165);
  // Columns are evenly spaced: 900 mm / 276 intervals.
  EXPECT_NEAR(p[1].x_mm - p[0].x_mm, 900.0 / 276, 1e-12);
}

// Ten classes of width 0.09 m from 0.10 m to 1.00 m (Maidi et al. 2010 §3.3).
TEST(SweepPlanPaper, TrueDistancesOnTheSimulatedRigCoverTheTenDistanceClasses) {
  const vision::RigGeometry rig =
      vision::RigGeometry::load(std::string(RIG_SOURCE_DIR) + "/config/rigs/sim.toml");
  const SweepPlan plan = SweepPlan::paper(0, 900, 135, 165);
  std::vector<int> per_class(10, 0);
  // The range ends are only reached up to the lateral offset of the outer rows
  // (15 mm at 0.1 m lengthens the distance by ~1.1 mm, at 1 m by ~0.1 mm)
  // and the mount's sub-degree misalignment (which moves the optical centre
  // not at all: the offset is zero). Allow 2 mm beyond either end.
  constexpr double kEndSlackM = 0.002;
  for (const PlanPosition& p : plan.positions()) {
    const double d = rig.distance_m(p.x_mm, p.y_mm);
    ASSERT_GE(d, 0.10 - kEndSlackM) << p.x_mm << ", " << p.y_mm;
    ASSERT_LE(d, 1.00 + kEndSlackM) << p.x_mm << ", " << p.y_mm;
    const int k = std::min(9, std::max(0, static_cast<int>(std::floor((d - 0.10) / 0.09))));
    ++per_class[k];
  }
  for (int k = 0; k < 10; ++k) {
    // 277 columns over 900 mm put ~27.7 columns in each 90 mm class, 7 rows each.
    EXPECT_GE(per_class[k], 7 * 27) << "class " << k;
  }
}

TEST(SweepPlanPaper, RefusesAnEmptyBox) {
  EXPECT_EQ(plan_error([] { SweepPlan::paper(0, 900, 150, 150); }),
            "paper plan: y range 150..150 mm: expected finite numbers with min < max");
}

TEST(SweepPlanJson, RoundTripsExactly) {
  const SweepPlan plan = SweepPlan::grid({0.1, 900, 13.7, 100.3, 200, 33.3, true});
  const nlohmann::json json = plan.to_json();
  // Through text, as it is stored in the run database.
  const SweepPlan back = SweepPlan::from_json(nlohmann::json::parse(json.dump()));
  EXPECT_EQ(back.description(), plan.description());
  EXPECT_EQ(xy(back), xy(plan));
  EXPECT_EQ(json["positions"][1][0].get<double>(), 0.1 + 13.7);
}

TEST(SweepPlanJson, RefusesMalformedPlansNamingTheElement) {
  using nlohmann::json;
  struct Case {
    json input;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {json::array(),
       "plan JSON: a array: expected an object {\"description\": ..., \"positions\": [[x, y], "
       "...]}"},
      {json{{"positions", {{1, 2}}}}, "plan JSON: description: expected a string"},
      {json{{"description", "d"}}, "plan JSON: positions: expected an array of [x, y]"},
      {json{{"description", "d"}, {"positions", json::array()}},
       "plan JSON: positions = []: expected at least one position"},
      {json{{"description", "d"}, {"positions", {{1, 2}, {3}}}},
       "plan JSON: positions[1] = [3]: expected [x_mm, y_mm], two finite numbers"},
      {json{{"description", "d"}, {"positions", {{1, "2"}}}},
       "plan JSON: positions[0] = [1,\"2\"]: expected [x_mm, y_mm], two finite numbers"},
      {json{{"description", "d"}, {"positions", {{1, 2}}}, {"extra", 1}},
       "plan JSON: unknown key \"extra\": expected only description and positions"},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(plan_error([&] { SweepPlan::from_json(c.input); }), c.expected) << c.input.dump();
  }
}

}  // namespace
