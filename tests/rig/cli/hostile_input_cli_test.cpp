// Input built to break a parser, given to the rig program as a user could:
// nesting deep enough to exhaust the stack of a recursive reader, numbers
// beyond a double, a folder where a file belongs, a database whose values
// no rig measured. Each must end in a clean exit 2 whose message names the
// input and what was expected, never a signal (run_rig gives -1 then).
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "rig_command.hpp"
#include "synthetic_run.hpp"

namespace {

namespace fs = std::filesystem;
using rig_test::RigRun;
using rig_test::run_rig;

const std::string kSampleProblem =
    std::string(RIG_SOURCE_DIR) + "/config/problems/paper_marker.json";

class HostileInput : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "rig-hostile-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  std::string write(const std::string& name, const std::string& text) const {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }
  fs::path dir_;
};

std::string nested(int depth, const std::string& inner) {
  return std::string(static_cast<std::size_t>(depth), '[') + inner +
         std::string(static_cast<std::size_t>(depth), ']');
}

// The sample problem as text with `key`'s value replaced by `value_text`.
std::string sample_with(const std::string& key, const std::string& value_text) {
  std::ifstream in(kSampleProblem);
  nlohmann::json j = nlohmann::json::parse(in);
  j[key] = "@VALUE@";
  std::string text = j.dump();
  text.replace(text.find("\"@VALUE@\""), 9, value_text);
  return text;
}

TEST_F(HostileInput, SolveRefusesAProblemNestedOneHundredThousandDeep) {
  const std::string points = "[[0,0,0]," + nested(100000, "1") + ",[1,0,0],[0,1,0]]";
  const std::string problem = write("deep.json", sample_with("object_points", points));
  const RigRun r = run_rig("solve " + problem + " --json");
  EXPECT_EQ(r.exit_code, 2) << r.err.substr(0, 300);
  EXPECT_EQ(r.err.rfind("rig solve: problem '" + problem +
                            "': nests arrays or objects more than "
                            "64 levels deep; expected at most 64",
                        0),
            0u)
      << r.err.substr(0, 300);
}

TEST_F(HostileInput, SolveNamesTheProblemOfANumberBeyondADouble) {
  std::ifstream in(kSampleProblem);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  nlohmann::json j = nlohmann::json::parse(text);
  j["camera"]["fy"] = "@FY@";
  text = j.dump();
  text.replace(text.find("\"@FY@\""), 6, "1e999999");
  const std::string problem = write("overflow.json", text);
  const RigRun r = run_rig("solve " + problem);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("rig solve: problem '" + problem + "': holds a value JSON cannot", 0), 0u)
      << r.err;
  EXPECT_NE(r.err.find("number overflow"), std::string::npos) << r.err;
}

TEST_F(HostileInput, SolveQuotesOnlyAnExcerptOfAHugeBadPoint) {
  // One point of 200,000 numbers: the message quotes 80 characters of it.
  std::string big = "[";
  for (int i = 0; i < 200000; ++i)
    big += (i ? ",1" : "1");
  big += "]";
  const std::string problem =
      write("wide.json", sample_with("object_points", "[" + big + ",[0,0,0],[1,0,0],[0,1,0]]"));
  const RigRun r = run_rig("solve " + problem);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("object_points[0] must be an array of 3 numbers"), std::string::npos)
      << r.err.substr(0, 300);
  EXPECT_LT(r.err.size(), 400u) << "an excerpt, not the point";
}

TEST_F(HostileInput, DetectRefusesACalibrationNestedTwoHundredThousandDeep) {
  const std::string calibration = write("deep.yaml", "%YAML:1.0\nx: " + nested(200000, "1") + "\n");
  const std::string image = write("unused.png", "");
  const RigRun r = run_rig("detect " + image + " --camera " + calibration);
  EXPECT_EQ(r.exit_code, 2) << r.err.substr(0, 300);
  EXPECT_EQ(r.err, "rig detect: calibration file '" + calibration +
                       "': line 2: a collection inside a sequence; expected numbers or strings "
                       "separated by ','\n");
}

TEST_F(HostileInput, DetectRefusesDeepXmlAndBlockYamlCalibrations) {
  std::string xml = "<?xml version=\"1.0\"?>\n<opencv_storage>";
  for (int i = 0; i < 100000; ++i)
    xml += "<a>";
  const std::string xml_file = write("deep.xml", xml);
  const RigRun x = run_rig("detect none.png --camera " + xml_file);
  EXPECT_EQ(x.exit_code, 2);
  EXPECT_NE(x.err.find("'" + xml_file + "': line 2: elements nested more than 32"),
            std::string::npos)
      << x.err.substr(0, 300);
  // "- - - - ... 1": one block sequence per "- ", two bytes a level.
  std::string dashes = "%YAML:1.0\nx:\n";
  for (int i = 0; i < 200000; ++i)
    dashes += "- ";
  const std::string yaml_file = write("dashes.yaml", dashes + "1\n");
  const RigRun y = run_rig("detect none.png --camera " + yaml_file);
  EXPECT_EQ(y.exit_code, 2);
  EXPECT_NE(y.err.find("'" + yaml_file + "': line 3: a block sequence item '- - - "),
            std::string::npos)
      << y.err.substr(0, 300);
}

// Found by fuzzing (tests/fuzz/calibration.cpp): a calibration whose top
// level is a list made OpenCV assert inside FileNode::operator[]; rig's YAML
// reader takes only KEY: VALUE lines.
TEST_F(HostileInput, DetectRefusesACalibrationWhoseTopLevelIsNotAMap) {
  const std::string calibration = write("list.yaml", "%YAML:1.0\n---\n- 1\n- 2\n");
  const RigRun r = run_rig("detect none.png --camera " + calibration);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err, "rig detect: calibration file '" + calibration +
                       "': line 3: a block sequence item '- 1'; expected KEY: VALUE (a sequence "
                       "is written [a, b, ...])\n");
}

TEST_F(HostileInput, DetectOfAFolderSaysItIsAFolder) {
  const RigRun r = run_rig("detect " + dir_.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "rig detect: image '" + dir_.string() +
                       "': is a directory; expected an image file (PNG, JPEG, TIFF, PGM/PPM or "
                       "BMP)\n");
  const RigRun c = run_rig("detect none.png --camera " + dir_.string());
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_NE(c.err.find("calibration file '" + dir_.string() + "': is not a regular file"),
            std::string::npos)
      << c.err;
}

// A true distance of 1e308 m is finite, but its square is not: the report
// names the database instead of a statistics function.
TEST_F(HostileInput, ReportNamesTheDatabaseOfAValueBeyondAnyPhysicalRange) {
  const std::string db = (dir_ / "run.db").string();
  rig_test::SyntheticRunSpec spec;
  spec.seed = 7;
  spec.positions = 20;
  spec.solvers = rig_test::paper_like_solvers();
  rig_test::write_synthetic_run(db, spec);
  sqlite3* connection = nullptr;
  ASSERT_EQ(sqlite3_open(db.c_str(), &connection), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(connection, "UPDATE positions SET true_distance_m = 1e308", nullptr,
                         nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(connection);
  const RigRun r = run_rig("report " + db + " --out " + (dir_ / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("rig report: " + db + ": run 1: cannot be reported: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("expected a database written by rig sweep"), std::string::npos) << r.err;
}

// Text that is not UTF-8 (a damaged database; found by the mutation test):
// nlohmann's dump threw, and rig report ended with exit 1 naming nothing.
// The report is written, its JSON valid, the bytes replaced by U+FFFD.
TEST_F(HostileInput, ReportOfADatabaseHoldingBytesThatAreNotUtf8IsValidJson) {
  const std::string db = (dir_ / "run.db").string();
  rig_test::SyntheticRunSpec spec;
  spec.seed = 7;
  spec.positions = 8;
  spec.solvers = rig_test::paper_like_solvers();
  rig_test::write_synthetic_run(db, spec);
  sqlite3* connection = nullptr;
  ASSERT_EQ(sqlite3_open(db.c_str(), &connection), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(connection, "UPDATE runs SET host = CAST(X'6C6162B7' AS TEXT)", nullptr,
                         nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(connection);
  const RigRun r = run_rig("report " + db + " --out " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(dir_ / "out" / "report.json");
  const nlohmann::json report = nlohmann::json::parse(in, nullptr, false);
  ASSERT_FALSE(report.is_discarded());
  EXPECT_NE(report.dump().find("lab\xEF\xBF\xBD"), std::string::npos);
}

}  // namespace
