// Replay of a recorded sweep: the replay bench, the replay frame
// source and the replay's configuration checks, on a run database and PNG
// frames written here (replay_sweep_test.cpp runs the real program).
#include "rig/sweep/replay.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "db/store/sha256.hpp"
#include "db/store/store.hpp"
#include "motion/errors.hpp"
#include "vision/image_codecs.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// A run database written directly through db::store::Store, with PNG frames on disk:
// what `rig sweep` with save_frames leaves behind, without the rig.
class RecordedRunFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rig_replay_unit_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    store_ = std::make_unique<db::store::Store>((dir_ / "run.db").string());
  }
  void TearDown() override {
    store_.reset();
    fs::remove_all(dir_);
  }

  // A grey ramp whose pixels depend on `seed`, so that every frame differs.
  std::string write_png(const std::string& name, int seed, int width = 736, int height = 571) {
    cv::Mat image(height, width, CV_8UC1);
    for (int r = 0; r < height; ++r)
      for (int c = 0; c < width; ++c)
        image.at<unsigned char>(r, c) = static_cast<unsigned char>((r + 3 * c + 17 * seed) % 256);
    const std::string path = (dir_ / name).string();
    vision::imwrite(path, image);
    return path;
  }

  // Starts a run whose plan is `xy`, mm.
  std::int64_t start_run(const std::vector<std::pair<double, double>>& xy) {
    nlohmann::json positions = nlohmann::json::array();
    for (const auto& [x, y] : xy)
      positions.push_back({x, y});
    db::store::RunDescription d;
    d.config_json = "{}";
    d.plan_json =
        rig::sweep::SweepPlan::from_json({{"description", "test plan"}, {"positions", positions}})
            .to_json()
            .dump();
    d.plan_size = static_cast<std::int64_t>(xy.size());
    d.library_versions_json = "{}";
    return store_->start_run(d);
  }

  // An ok position at the plan's XY, measured 1 µm off, with `frames` saved PNGs.
  // Position 0 of a one-position run at (400, 150), read back there, with
  // the given frames.
  void append_at_400_150(std::int64_t run, std::vector<db::store::FrameRecord> frames) {
    db::store::PositionRecord p;
    p.commanded_x_mm = p.measured_x_mm.emplace(400);
    p.commanded_y_mm = p.measured_y_mm.emplace(150);
    p.frames = std::move(frames);
    store_->append_position(run, p);
  }

  void append_ok(std::int64_t run, std::int64_t index, double x, double y, int frames) {
    db::store::PositionRecord p;
    p.plan_index = index;
    p.commanded_x_mm = x;
    p.commanded_y_mm = y;
    p.measured_x_mm = x + 0.001;
    p.measured_y_mm = y - 0.001;
    for (int k = 0; k < frames; ++k) {
      db::store::FrameRecord f;
      f.index = k;
      f.image_path = write_png("r" + std::to_string(run) + "p" + std::to_string(index) + "_f" +
                                   std::to_string(k) + ".png",
                               static_cast<int>(10 * index + k));
      f.image_sha256 = db::store::sha256_hex(file_bytes(*f.image_path));
      p.frames.push_back(f);
    }
    store_->append_position(run, p);
  }

  void append_failed(std::int64_t run, std::int64_t index, double x, double y, bool read_back,
                     const std::string& reason) {
    db::store::PositionRecord p;
    p.plan_index = index;
    p.commanded_x_mm = x;
    p.commanded_y_mm = y;
    if (read_back) {
      p.measured_x_mm = x;
      p.measured_y_mm = y;
    }
    p.status = db::store::PositionStatus::kFailed;
    p.failure_reason = reason;
    store_->append_position(run, p);
  }

  struct Replay {
    std::shared_ptr<const rig::sweep::RecordedRun> run;
    std::shared_ptr<rig::sweep::ReplayCursor> cursor;
    std::unique_ptr<rig::sweep::ReplayBench> bench;
    std::unique_ptr<rig::sweep::ReplayFrames> frames;
  };
  Replay replay(std::int64_t run) {
    Replay r;
    r.run = std::make_shared<const rig::sweep::RecordedRun>(
        rig::sweep::RecordedRun::load(*store_, run));
    r.cursor = std::make_shared<rig::sweep::ReplayCursor>(r.run);
    r.bench = std::make_unique<rig::sweep::ReplayBench>(r.cursor);
    r.frames = std::make_unique<rig::sweep::ReplayFrames>(r.cursor);
    r.frames->open();
    return r;
  }

  static rig::sweep::SweepConfig config(int frames_per_position) {
    rig::sweep::SweepConfig c;
    c.sweep_file = "/abs/replay.toml";
    c.frames_per_position = frames_per_position;
    c.frames_dir = "/abs/frames";
    return c;  // the paper camera: 736x571
  }

  fs::path dir_;
  std::unique_ptr<db::store::Store> store_;
};

TEST_F(RecordedRunFixture, TheBenchSelectsThePositionByCommandedXyAndReportsItsRecordedReadBack) {
  const std::int64_t run = start_run({{400, 150}, {500, 150}});
  append_ok(run, 0, 400, 150, 1);
  append_ok(run, 1, 500, 150, 1);
  Replay r = replay(run);
  r.bench->move_to(500, 150);
  const motion::BenchStatus s = r.bench->wait_settled(1000ms);
  EXPECT_EQ(s.position.x_mm, 500.001);
  EXPECT_EQ(s.position.y_mm, 149.999);
  EXPECT_TRUE(s.homed);
  EXPECT_TRUE(s.in_position);
  EXPECT_FALSE(s.moving);
  EXPECT_EQ(r.bench->position().x_mm, 500.001);
  ASSERT_NE(r.cursor->selected(), nullptr);
  EXPECT_EQ(r.cursor->selected()->plan_index, 1);
}

TEST_F(RecordedRunFixture, TheBenchRefusesAnXyTheRecordedPlanDoesNotHaveNamingIt) {
  const std::int64_t run = start_run({{400, 150}});
  append_ok(run, 0, 400, 150, 1);
  Replay r = replay(run);
  // 1e-5 mm off is ten times the match tolerance.
  try {
    r.bench->move_to(400.00001, 150);
    FAIL() << "no error";
  } catch (const motion::SoftLimitError& e) {
    EXPECT_NE(std::string(e.what()).find("move to (400.00001, 150) mm"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("run 1 of"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(r.bench->move_to(400 + 0.5e-6, 150));
}

TEST_F(RecordedRunFixture, TheFramesAreTheSavedPngsInOrderWithTheirPathsAsOrigin) {
  const std::int64_t run = start_run({{400, 150}});
  append_ok(run, 0, 400, 150, 2);
  Replay r = replay(run);
  r.bench->move_to(400, 150);
  r.bench->wait_settled(1000ms);
  const auto before = std::chrono::system_clock::now();
  for (int k = 0; k < 2; ++k) {
    r.frames->trigger();
    const vision::Frame f = r.frames->grab(1000ms);
    const std::string path = (dir_ / ("r1p0_f" + std::to_string(k) + ".png")).string();
    EXPECT_EQ(f.origin, path);
    EXPECT_EQ(f.frame_id, static_cast<std::uint64_t>(k));
    EXPECT_GE(f.host_time, before);  // the controller's "exposed after settled" check
    const cv::Mat expected = vision::imread(path, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(f.image.type(), CV_8UC1);
    EXPECT_EQ(cv::norm(f.image, expected, cv::NORM_INF), 0.0) << k;
  }
  EXPECT_THROW(r.frames->grab(1000ms), vision::EndOfFrames);
  EXPECT_EQ(r.frames->counters().delivered, 2u);
}

TEST_F(RecordedRunFixture, AChangedPngIsACaptureErrorNamingTheFileAndTheHashes) {
  const std::int64_t run = start_run({{400, 150}});
  append_ok(run, 0, 400, 150, 1);
  const std::string path = (dir_ / "r1p0_f0.png").string();
  const std::string stored = db::store::sha256_hex(file_bytes(path));
  std::ofstream(path, std::ios::binary | std::ios::app) << '\0';  // still a valid PNG
  const std::string now = db::store::sha256_hex(file_bytes(path));
  Replay r = replay(run);
  r.bench->move_to(400, 150);
  r.bench->wait_settled(1000ms);
  try {
    r.frames->grab(1000ms);
    FAIL() << "no error";
  } catch (const vision::CaptureError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("replay of run 1 of " + store_->path() + ": position 0, frame 0: ", 0), 0u)
        << what;
    EXPECT_NE(what.find("recorded frame " + path + " has SHA-256 " + now.substr(0, 12) +
                        "... but the run stored " + stored.substr(0, 12) + "..."),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("the file changed since it was recorded"), std::string::npos) << what;
  }
}

TEST_F(RecordedRunFixture, AMissingPngIsACaptureErrorNamingTheFile) {
  const std::int64_t run = start_run({{400, 150}});
  append_ok(run, 0, 400, 150, 1);
  const std::string path = (dir_ / "r1p0_f0.png").string();
  fs::remove(path);
  Replay r = replay(run);
  r.bench->move_to(400, 150);
  r.bench->wait_settled(1000ms);
  try {
    r.frames->grab(1000ms);
    FAIL() << "no error";
  } catch (const vision::CaptureError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot read recorded frame " + path), std::string::npos)
        << e.what();
  }
}

TEST_F(RecordedRunFixture, PositionsTheRunDidNotMeasureFailAgainSayingWhy) {
  const std::int64_t run = start_run({{400, 150}, {500, 150}, {600, 150}, {700, 150}});
  append_ok(run, 0, 400, 150, 1);
  append_failed(run, 1, 500, 150, true, "camera: gige:127.0.0.1: no frame within 2000 ms");
  append_failed(run, 2, 600, 150, false, "settle: not settled within 25000 ms");
  store_->finish_run(run, db::store::RunStatus::kAborted, "SIGINT received (after position 2)");
  Replay r = replay(run);

  // A camera failure: the read-back is there, the frames are not.
  r.bench->move_to(500, 150);
  EXPECT_EQ(r.bench->wait_settled(1000ms).position.x_mm, 500);
  try {
    r.frames->grab(1000ms);
    FAIL() << "no error";
  } catch (const vision::CaptureError& e) {
    EXPECT_EQ(std::string(e.what()), "replay of run 1 of " + store_->path() +
                                         ": position 1 has no recorded frames (it failed: camera: "
                                         "gige:127.0.0.1: no frame within 2000 ms)");
  }
  // A settle failure: no read-back.
  r.bench->move_to(600, 150);
  try {
    r.bench->wait_settled(1000ms);
    FAIL() << "no error";
  } catch (const motion::BenchTimeout& e) {
    EXPECT_EQ(std::string(e.what()),
              "position 2 of run 1 of " + store_->path() +
                  " has no recorded read-back (it failed: settle: not settled within 25000 ms)");
  }
  // Never measured: the run was aborted before.
  r.bench->move_to(700, 150);
  try {
    r.bench->wait_settled(1000ms);
    FAIL() << "no error";
  } catch (const motion::BenchTimeout& e) {
    EXPECT_NE(std::string(e.what()).find("it was never measured (run 1 ended aborted: SIGINT "
                                         "received (after position 2))"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(RecordedRunFixture, APlanThatRevisitsAPointIsReplayedInPlanOrder) {
  const std::int64_t run = start_run({{400, 150}, {500, 150}, {400, 150}});
  for (std::int64_t i = 0; i < 3; ++i)
    append_ok(run, i, i == 1 ? 500 : 400, 150, 1);
  Replay r = replay(run);
  std::vector<std::int64_t> visited;
  for (const double x : {400.0, 500.0, 400.0}) {
    r.bench->move_to(x, 150);
    r.bench->move_to(x, 150);  // moving again before settling stays at the same position
    r.bench->wait_settled(1000ms);
    visited.push_back(r.cursor->selected()->plan_index);
    EXPECT_EQ(r.frames->grab(1000ms).origin,
              (dir_ / ("r1p" + std::to_string(visited.back()) + "_f0.png")).string());
  }
  EXPECT_EQ(visited, (std::vector<std::int64_t>{0, 1, 2}));
}

TEST_F(RecordedRunFixture, TheReplayConfigTurnsSavingOffAndVisitsEveryPosition) {
  const std::int64_t run = start_run({{400, 150}, {500, 150}});
  append_ok(run, 0, 400, 150, 2);
  append_ok(run, 1, 500, 150, 3);
  const rig::sweep::RecordedRun recorded = rig::sweep::RecordedRun::load(*store_, run);
  EXPECT_EQ(recorded.saved_frames_per_position(), 2);  // the fewest of an ok position
  const rig::sweep::SweepConfig c = rig::sweep::replay_config(config(2), recorded);
  EXPECT_FALSE(c.frames_dir.has_value());
  EXPECT_GT(c.faults.max_consecutive_failed_positions, 2);
  EXPECT_EQ(c.frames_per_position, 2);
}

TEST_F(RecordedRunFixture, MoreFramesPerPositionThanTheRunSavedAreRefusedNamingBoth) {
  const std::int64_t run = start_run({{400, 150}});
  append_ok(run, 0, 400, 150, 2);
  const rig::sweep::RecordedRun recorded = rig::sweep::RecordedRun::load(*store_, run);
  try {
    rig::sweep::replay_config(config(3), recorded);
    FAIL() << "no error";
  } catch (const rig::sweep::RunMismatch& e) {
    EXPECT_EQ(std::string(e.what()),
              "/abs/replay.toml: capture.frames_per_position = 3 but run 1 of " + store_->path() +
                  " saved 2 frames per position; expected at most 2 for a replay of it");
  }
}

TEST_F(RecordedRunFixture, ARunWithoutSavedFramesCannotBeReplayed) {
  const std::int64_t run = start_run({{400, 150}});
  std::vector<db::store::FrameRecord> frames(2);  // frames measured, none saved
  frames[1].index = 1;
  append_at_400_150(run, frames);
  const rig::sweep::RecordedRun recorded = rig::sweep::RecordedRun::load(*store_, run);
  EXPECT_EQ(recorded.saved_frames_per_position(), 0);
  try {
    rig::sweep::replay_config(config(1), recorded);
    FAIL() << "no error";
  } catch (const rig::sweep::RunMismatch& e) {
    EXPECT_EQ(std::string(e.what()),
              "run 1 of " + store_->path() +
                  " saved no frames (set [capture] save_frames in the sweep file)");
  }
}

TEST_F(RecordedRunFixture, FramesOfAnotherSizeThanTheCalibrationAreRefused) {
  const std::int64_t run = start_run({{400, 150}});
  db::store::FrameRecord f;
  f.image_path = write_png("vga.png", 1, 640, 480);
  f.image_sha256 = db::store::sha256_hex(file_bytes(*f.image_path));
  append_at_400_150(run, {f});
  try {
    rig::sweep::replay_config(config(1), rig::sweep::RecordedRun::load(*store_, run));
    FAIL() << "no error";
  } catch (const rig::sweep::RunMismatch& e) {
    EXPECT_NE(std::string(e.what()).find("capture.calibration: the built-in paper camera "
                                         "(capture.calibration = \"\") is for 736x571 px but "
                                         "frame " +
                                         *f.image_path + " of run 1 of " + store_->path() +
                                         " is 640x480 px"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
