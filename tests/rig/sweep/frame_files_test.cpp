// Where saved frames go and how they are written (rig/sweep/frame_files.hpp):
// only new files, never through a link, in a folder of one database and run.
#include "rig/sweep/frame_files.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include "file_bytes.hpp"

namespace {

namespace fs = std::filesystem;
using rig::sweep::database_frames_folder;
using rig::sweep::prepare_frames_folder;
using rig::sweep::run_frames_folder;
using rig::sweep::write_new_file;

class FrameFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "rig-frame-files-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ignored;
    fs::permissions(dir_, fs::perms::owner_all, fs::perm_options::add, ignored);
    fs::remove_all(dir_, ignored);
  }
  fs::path dir_;
};

TEST_F(FrameFiles, TwoDatabasesNeverShareAFolderAndOneDatabaseAlwaysGetsTheSame) {
  const std::string frames = (dir_ / "frames").string();
  const fs::path a = database_frames_folder(frames, (dir_ / "a/run.db").string());
  const fs::path b = database_frames_folder(frames, (dir_ / "b/run.db").string());
  EXPECT_NE(a, b);
  EXPECT_EQ(a.parent_path(), fs::path(frames));
  EXPECT_EQ(a.filename().string().rfind("run-", 0), 0u) << a;
  EXPECT_EQ(a.filename().string().size(), std::string("run-").size() + 12);
  // A relative and an absolute spelling of one database are one folder.
  const fs::path cwd = fs::current_path();
  fs::current_path(dir_);
  EXPECT_EQ(database_frames_folder(frames, "a/run.db"), a);
  fs::current_path(cwd);
  EXPECT_EQ(run_frames_folder(frames, (dir_ / "a/run.db").string(), 3), a / "run3");
}

TEST_F(FrameFiles, APlantedLinkIsNeitherFollowedNorReplacedAndItsTargetIsKept) {
  const fs::path target = dir_ / "precious.txt";
  std::ofstream(target) << "precious";
  const fs::path frame = dir_ / "p0_f0.png";
  fs::create_symlink(target, frame);
  for (const bool replace_leftover : {false, true}) {
    try {
      write_new_file(frame, "PNG", replace_leftover);
      FAIL() << "wrote through " << frame;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(frame.string() + ": exists already"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_EQ(rig_test::file_bytes(target), "precious");
  EXPECT_TRUE(fs::is_symlink(frame));
}

TEST_F(FrameFiles, AnExistingFileIsKeptUnlessItIsThisRunsLeftover) {
  const fs::path frame = dir_ / "p0_f0.png";
  write_new_file(frame, "first", false);
  EXPECT_EQ(rig_test::file_bytes(frame), "first");
  EXPECT_THROW(write_new_file(frame, "second", false), std::runtime_error);
  EXPECT_EQ(rig_test::file_bytes(frame), "first");
  write_new_file(frame, "second", true);
  EXPECT_EQ(rig_test::file_bytes(frame), "second");
}

TEST_F(FrameFiles, AFolderThatIsAFileOrALinkOrReadOnlyIsRefusedNamingIt) {
  const fs::path file = dir_ / "run1";
  std::ofstream(file) << "x";
  EXPECT_THROW(prepare_frames_folder(file), std::runtime_error);
  const fs::path link = dir_ / "link";
  fs::create_directory(dir_ / "elsewhere");
  fs::create_symlink(dir_ / "elsewhere", link);
  try {
    prepare_frames_folder(link);
    FAIL() << "accepted a link";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(link.string() + ": is a symbolic link"), std::string::npos)
        << e.what();
  }
  if (::geteuid() != 0) {  // root writes into a read-only folder anyway
    const fs::path locked = dir_ / "locked";
    fs::create_directory(locked);
    fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec);
    EXPECT_THROW(prepare_frames_folder(locked / "run1"), std::runtime_error);
  }
  prepare_frames_folder(dir_ / "new/run1");
  EXPECT_TRUE(fs::is_directory(dir_ / "new/run1"));
  EXPECT_TRUE(fs::is_empty(dir_ / "new/run1")) << "the write check leaves nothing behind";
}

}  // namespace
