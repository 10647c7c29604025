// rig's exit codes and error lines (rig/cli/src/exit_codes.hpp) as a user
// meets them, for the commands whose one error type means two things: an
// artwork error is bad input (2) when it is the file name or a value, a
// failure (1) when the file cannot be written.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <string>

#include "rig_command.hpp"

namespace {

namespace fs = std::filesystem;
using rig_test::RigRun;
using rig_test::run_rig;

class RigExitCodes : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "rig-exit-codes-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  // A path whose folder does not exist: the file cannot be created.
  std::string unwritable(const std::string& name) const { return file("missing/" + name); }

  const std::string layout_ = std::string(RIG_SOURCE_DIR) + "/config/targets/paper.toml";
  fs::path dir_;
};

TEST_F(RigExitCodes, AMarkerWithAnUnknownExtensionOrIdIsBadInput) {
  const RigRun extension = run_rig("marker --id 0 --out " + file("m.txt"));
  EXPECT_EQ(extension.exit_code, 2);
  EXPECT_EQ(extension.err.rfind("rig marker: " + file("m.txt") + ": unknown extension", 0), 0u)
      << extension.err;
  const RigRun id = run_rig("marker --id 35 --out " + file("m.svg"));
  EXPECT_EQ(id.exit_code, 2);
  EXPECT_EQ(id.err, "rig marker: --id 35: expected 0 .. 34 (the ids of rig4x4)\n");
  EXPECT_FALSE(fs::exists(file("m.svg")));
}

TEST_F(RigExitCodes, AMarkerThatCannotBeWrittenIsAFailure) {
  const RigRun r = run_rig("marker --id 0 --out " + unwritable("m.svg"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err.rfind("rig marker: " + unwritable("m.svg") + ": cannot", 0), 0u) << r.err;
  EXPECT_EQ(run_rig("marker --id 0 --out " + file("m.svg")).exit_code, 0);
}

TEST_F(RigExitCodes, ATargetWithAMissingLayoutIsBadInputAndAnUnwritableSheetAFailure) {
  const RigRun layout = run_rig("target --target " + file("none.toml") + " --out " + file("t.svg"));
  EXPECT_EQ(layout.exit_code, 2);
  EXPECT_EQ(layout.err.rfind("rig target: " + file("none.toml") + ": ", 0), 0u) << layout.err;
  const RigRun sheet = run_rig("target --target " + layout_ + " --out " + unwritable("t.svg"));
  EXPECT_EQ(sheet.exit_code, 1);
  EXPECT_EQ(sheet.err.rfind("rig target: " + unwritable("t.svg") + ": cannot", 0), 0u) << sheet.err;
}

TEST_F(RigExitCodes, ACameraSpecRigDoesNotKnowIsBadInput) {
  const RigRun r = run_rig("capture --camera usb:0 --out " + file("frames"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err.rfind("rig capture: camera spec 'usb:0': expected ", 0), 0u) << r.err;
}

}  // namespace
