// The top of the page: the run header names what was measured with what,
// the summary table comes first with one row per solver and scope in the
// units an engineer reads (mm or µm, µs, %), and the page's numbers never
// use e-notation.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "db/report/report.hpp"
#include "db/store/store.hpp"
#include "file_bytes.hpp"
#include "report_units.hpp"
#include "store_fixture.hpp"
#include "synthetic_run.hpp"

namespace {

using db::report::DisplayUnit;
using db::report::Quantity;

TEST(ReportUnits, PicksTheUnitAndDecimalsFromTheColumnsLargestValue) {
  // 2.8 mm: mm with 3 decimals (four significant digits of the largest).
  const DisplayUnit mm = db::report::display_unit(Quantity::kLength, 0.00280016);
  EXPECT_EQ(mm.symbol, "mm");
  EXPECT_EQ(db::report::fixed(0.00280016, mm), "2.800");
  EXPECT_EQ(db::report::fixed(0.0000153, mm), "0.015");
  // Below 1 mm: µm; 35.2 µm has two digits before the point, two after.
  const DisplayUnit um = db::report::display_unit(Quantity::kLength, 35.2e-6);
  EXPECT_EQ(um.symbol, "µm");
  EXPECT_EQ(db::report::fixed(35.2e-6, um), "35.20");
  // Stage times of 17.5 µs and 1.2 ms: ms, 1.200 and 0.018.
  const DisplayUnit ms = db::report::display_unit(Quantity::kDuration, 1.2e-3);
  EXPECT_EQ(ms.symbol, "ms");
  EXPECT_EQ(db::report::fixed(1.76e-5, ms), "0.018");
  EXPECT_EQ(db::report::display_unit(Quantity::kDuration, 1.75e-5).symbol, "µs");
  // Rates in % (100 % has three digits: one decimal), slopes with their fourth decimal, NaN as n/a,
  // no "-0".
  EXPECT_EQ(db::report::fixed(0.956, db::report::display_unit(Quantity::kFraction, 1.0)), "95.6");
  EXPECT_EQ(db::report::fixed(1.0084, db::report::display_unit(Quantity::kPlain, 1.0084)),
            "1.0084");
  EXPECT_EQ(db::report::fixed(std::nan(""), mm), "n/a");
  EXPECT_EQ(db::report::fixed(-1e-9, mm), "0.000");
  EXPECT_EQ(db::report::length_text(1e-7), "0.1000 µm");
}

TEST(ReportUnits, RewritesAColumnAndItsHeaderKeepingOtherCells) {
  db::report::html::Table t{"t", "c", {"solver", "mean error (m)", "rate"}, {}};
  t.rows.push_back({{"lm", "", ""},
                    db::report::quantity_cell(0.0021, Quantity::kLength),
                    db::report::quantity_cell(0.5, Quantity::kFraction)});
  t.rows.push_back(
      {{"oi", "", ""}, db::report::quantity_cell(-0.0004, Quantity::kLength), {"n/a", "", ""}});
  // JSON and CSV keep SI with 6 significant digits.
  EXPECT_EQ(t.rows[0][1].text, "0.0021");
  const db::report::html::Table shown = db::report::display_table(t);
  EXPECT_EQ(shown.header[1], "mean error (mm)");
  EXPECT_EQ(shown.header[2], "rate (%)");
  EXPECT_EQ(shown.rows[0][1].text, "2.100");
  EXPECT_EQ(shown.rows[1][1].text, "-0.400");
  EXPECT_EQ(shown.rows[0][2].text, "50.00");
  EXPECT_EQ(shown.rows[1][2].text, "n/a");
  EXPECT_EQ(shown.rows[0][0].text, "lm");
}

class ReportSummary : public ::testing::Test {
 protected:
  void SetUp() override {
    rig_test::SyntheticRunSpec spec;
    spec.positions = 60;
    spec.solvers = rig_test::paper_like_solvers();
    rig_test::write_synthetic_run(dir_.file("run.db"), spec);
  }
  std::string page(const std::string& db) {
    const db::report::Report report(db, db::report::ReportOptions{});
    return rig_test::file_bytes(report.write(dir_.file("out")).html);
  }
  db_test::ScratchDir dir_;
};

TEST_F(ReportSummary, ComesFirstWithOneRowPerSolverAndScopeInMillimetres) {
  const std::string html = page(dir_.file("run.db"));
  const auto first_table = html.find("<table");
  ASSERT_NE(first_table, std::string::npos);
  EXPECT_EQ(html.find("<table id=\"summary\">"), first_table);
  const std::string summary =
      html.substr(first_table, html.find("</table>", first_table) - first_table);
  EXPECT_NE(summary.find("mean |error| (mm)"), std::string::npos) << summary;
  EXPECT_NE(summary.find("time per solve (µs)"), std::string::npos) << summary;
  EXPECT_NE(summary.find("failure rate (%)"), std::string::npos) << summary;
  // Four solvers, two scopes; analytic does not apply to the whole target.
  std::size_t rows = 0;
  for (auto at = summary.find("<tr>"); at != std::string::npos; at = summary.find("<tr>", at + 1))
    ++rows;
  EXPECT_EQ(rows, 1u + 8u) << summary;  // the heading and 8 rows
  EXPECT_NE(summary.find("n/a (does not apply)"), std::string::npos) << summary;
  // No table cell on the page is in e-notation.
  const std::regex e_notation("<td[^>]*>-?[0-9.]+e[-+][0-9]+</td>");
  EXPECT_FALSE(std::regex_search(html, e_notation));
}

TEST_F(ReportSummary, HeaderSaysWhenTheCameraWasNotRecorded) {
  const std::string html = page(dir_.file("run.db"));
  EXPECT_NE(html.find("<dt>Camera</dt><dd>camera not recorded</dd>"), std::string::npos);
  EXPECT_NE(html.find("<dt>Measured on</dt><dd>not recorded (camera not recorded)</dd>"),
            std::string::npos);
  // The stored files with their short hashes.
  db::store::Store store(dir_.file("run.db"));
  const db::store::Run run = store.run(1);
  EXPECT_NE(html.find("<dt>Sweep file</dt><dd>" + run.description.sweep_file.path + " (sha256 " +
                      run.description.sweep_file.sha256.substr(0, 12) + ")</dd>"),
            std::string::npos);
}

TEST_F(ReportSummary, HeaderNamesTheSimulatedRigAndItsRealism) {
  {
    db::store::Store store(dir_.file("run.db"));
    store.record_camera(
        1, {"gige:127.0.0.1", "rig-rig-sim-0001", "rig", "rig-sim", "0001", "realism harsh"});
  }
  const std::string html = page(dir_.file("run.db"));
  EXPECT_NE(html.find("<dd>simulated rig (realism: harsh)</dd>"), std::string::npos);
  EXPECT_NE(html.find("vendor rig, model rig-sim, serial 0001, device version realism harsh"),
            std::string::npos);
  {
    db::store::Store store(dir_.file("run.db"));
    store.record_camera(
        1, {"gige:192.168.1.20", "Basler-acA1300-123", "Basler", "acA1300", "123", "1.0"});
  }
  EXPECT_NE(page(dir_.file("run.db")).find("<dt>Measured on</dt><dd>bench</dd>"),
            std::string::npos);
  {
    db::store::Store store(dir_.file("run.db"));
    store.record_camera(
        1, {"gige:127.0.0.1", "Aravis-Fake-RIGSIM01", "Aravis", "Fake", "RIGSIM01", "0.8.26"});
  }
  EXPECT_NE(page(dir_.file("run.db")).find("<dd>simulated camera (Aravis fake GigE camera"),
            std::string::npos);
}

// Two solvers that compute the same pose share one summary row and one
// series per figure.
TEST_F(ReportSummary, ListsCoincidingSolversOnce) {
  rig_test::SyntheticRunSpec spec;
  spec.positions = 40;
  spec.solvers = rig_test::paper_like_solvers();
  spec.solvers.push_back(spec.solvers[1]);
  spec.solvers.back().name = "hybrid_oi_copy";
  spec.solvers.back().same_draws_as = spec.solvers[1].name;
  rig_test::write_synthetic_run(dir_.file("twins.db"), spec);
  const db::report::Report report(dir_.file("twins.db"), db::report::ReportOptions{});
  const db::report::SolverStudy* copy = report.study().find("hybrid_oi_copy", "0");
  ASSERT_NE(copy, nullptr);
  EXPECT_EQ(copy->coincides_with, "hybrid_oi");
  EXPECT_TRUE(report.study().find("ekf", "0")->coincides_with.empty());
  const std::string html = rig_test::file_bytes(report.write(dir_.file("out")).html);
  EXPECT_NE(html.find("Coinciding solvers, listed and drawn once: hybrid_oi = hybrid_oi_copy"),
            std::string::npos);
  const nlohmann::json json =
      nlohmann::json::parse(rig_test::file_bytes(dir_.file("out/report.json")));
  for (const auto& f : json["figures"])
    for (const auto& s : f["series"])
      EXPECT_EQ(s["label"].get<std::string>().rfind("hybrid_oi_copy", 0), std::string::npos)
          << f["id"];
}

}  // namespace
