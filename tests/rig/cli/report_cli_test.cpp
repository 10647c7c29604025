// `rig report` as a user runs it: the real binary on a synthetic run
// database, its three outputs and its exit codes.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "file_bytes.hpp"
#include "rig_command.hpp"
#include "store_fixture.hpp"
#include "synthetic_run.hpp"

namespace {

namespace fs = std::filesystem;
using rig_test::RigRun;
using rig_test::run_rig;

using Scratch = db_test::ScratchDir;

rig_test::SyntheticRunSpec spec(std::uint64_t seed) {
  rig_test::SyntheticRunSpec s;
  s.seed = seed;
  s.positions = 60;
  s.solvers = rig_test::paper_like_solvers();
  return s;
}

TEST(RigReport, WritesHtmlJsonAndCsvTables) {
  Scratch dir;
  rig_test::write_synthetic_run(dir.file("run.db"), spec(1));
  const RigRun r = run_rig("report " + dir.file("run.db") + " --out " + dir.file("out"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string html = rig_test::file_bytes(dir.file("out/report.html"));
  EXPECT_EQ(html.rfind("<!doctype html>", 0), 0u) << html.substr(0, 40);
  EXPECT_NE(html.find("<svg"), std::string::npos);
  const auto json = nlohmann::json::parse(rig_test::file_bytes(dir.file("out/report.json")));
  EXPECT_GT(json["figures"].size(), 10u);
  for (const auto& t : json["tables"]) {
    const std::string csv =
        rig_test::file_bytes(dir.file("out/" + t["id"].get<std::string>() + ".csv"));
    ASSERT_FALSE(csv.empty()) << t["id"];
    EXPECT_EQ(csv.substr(0, csv.find(',')), t["header"][0].get<std::string>());
  }
  EXPECT_TRUE(fs::exists(dir.file("out/table4-0.csv")));
}

TEST(RigReport, BadInputExitsWithTwoAndNamesTheFile) {
  Scratch dir;
  const RigRun missing = run_rig("report " + dir.file("missing.db") + " --out " + dir.file("o"));
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find(dir.file("missing.db")), std::string::npos) << missing.err;
  EXPECT_NE(missing.err.find("no such file"), std::string::npos) << missing.err;
  EXPECT_FALSE(fs::exists(dir.file("o/report.html")));

  rig_test::SyntheticRunSpec running = spec(1);
  running.positions = 10;
  running.status = db::store::RunStatus::kRunning;
  rig_test::write_synthetic_run(dir.file("running.db"), running);
  const RigRun none = run_rig("report " + dir.file("running.db") + " --out " + dir.file("o"));
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("no completed run"), std::string::npos) << none.err;

  const RigRun no_out = run_rig("report " + dir.file("running.db"));
  EXPECT_EQ(no_out.exit_code, 2) << no_out.err;
}

TEST(RigReport, RefusesArgumentsThatCannotGiveWhatWasAsked) {
  Scratch dir;
  rig_test::write_synthetic_run(dir.file("run.db"), spec(1));
  // A regression needs a baseline to regress from.
  const RigRun alone =
      run_rig("report " + dir.file("run.db") + " --fail-on-regression --out " + dir.file("o"));
  EXPECT_EQ(alone.exit_code, 2) << alone.err;
  EXPECT_NE(alone.err.find("--fail-on-regression without --baseline"), std::string::npos)
      << alone.err;
  EXPECT_FALSE(fs::exists(dir.file("o")));
  // --out naming a file: refused, naming it, and the file left as it was.
  std::ofstream(dir.file("notes.txt")) << "keep me";
  const RigRun onto_file =
      run_rig("report " + dir.file("run.db") + " --out " + dir.file("notes.txt"));
  EXPECT_EQ(onto_file.exit_code, 2) << onto_file.err;
  EXPECT_NE(onto_file.err.find(dir.file("notes.txt")), std::string::npos) << onto_file.err;
  EXPECT_NE(onto_file.err.find("existing file"), std::string::npos) << onto_file.err;
  EXPECT_EQ(rig_test::file_bytes(dir.file("notes.txt")), "keep me");
}

// Exit code 3 only with --fail-on-regression and only when a solver got
// significantly worse (a 10 mm larger intercept: z ~ 30, see
// tests/db/report_compare_test.cpp).
TEST(RigReport, FailOnRegressionExitsWithThree) {
  Scratch dir;
  rig_test::write_synthetic_run(dir.file("baseline.db"), spec(2));
  rig_test::write_synthetic_run(dir.file("same.db"), spec(3));
  rig_test::SyntheticRunSpec worse = spec(4);
  worse.solvers[1].intercept_m += 0.010;  // hybrid_oi
  rig_test::write_synthetic_run(dir.file("worse.db"), worse);

  const std::string base = " --baseline " + dir.file("baseline.db") + ":1 --out " + dir.file("o");
  const RigRun same = run_rig("report " + dir.file("same.db") + base + " --fail-on-regression");
  EXPECT_EQ(same.exit_code, 0) << same.out << same.err;
  const RigRun flagged = run_rig("report " + dir.file("worse.db") + base);
  EXPECT_EQ(flagged.exit_code, 0) << flagged.err;
  EXPECT_NE(flagged.out.find("worse: hybrid_oi"), std::string::npos) << flagged.out;
  const RigRun failed = run_rig("report " + dir.file("worse.db") + base + " --fail-on-regression");
  EXPECT_EQ(failed.exit_code, 3) << failed.out << failed.err;
  EXPECT_TRUE(fs::exists(dir.file("o/report.html")));  // written before failing
}

}  // namespace
