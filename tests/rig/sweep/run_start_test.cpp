// Starting the run a sweep measures into (rig/sweep/run_start.hpp): a new
// run, a resumed run and a replay, on a real run database, with a bench that
// counts what it is told (the real Modbus bench is driven end to end in
// sweep_e2e_test.cpp). What matters here is the order: checks before the
// bench moves, homing before anything is recorded, nothing recorded on an
// error or an abort.
#include "rig/sweep/run_start.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>

#include "db/store/sha256.hpp"
#include "rig/sweep/frame_files.hpp"
#include "rig/sweep/run_record.hpp"
#include "vision/image_codecs.hpp"

namespace {

namespace fs = std::filesystem;

// A bench that is homed when told to be; `on_home` runs inside home(), to
// look at the database at that moment.
class CountingBench : public motion::Bench {
 public:
  bool homed = false;
  int homes = 0;
  std::function<void()> on_home;

  void home() override {
    ++homes;
    if (on_home) on_home();
    homed = true;
  }
  void move_to(double x_mm, double y_mm) override { at_ = {x_mm, y_mm}; }
  motion::BenchStatus wait_settled(std::chrono::milliseconds) override { return status(); }
  motion::XY position() override { return at_; }
  motion::BenchStatus status() override {
    motion::BenchStatus s;
    s.position = at_;
    s.homed = homed;
    s.in_position = true;
    return s;
  }
  void stop() override {}
  void reset_alarm() override {}

 private:
  motion::XY at_;
};

class RunStartTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rig_run_start_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    config_ = rig::sweep::load_sweep_config(std::string(RIG_SOURCE_DIR) +
                                            "/config/sweeps/smoke.toml");  // home_first = true
    store_ = std::make_unique<db::store::Store>(
        rig::sweep::open_run_database((dir_ / "run.db").string(), config_));
  }
  void TearDown() override {
    store_.reset();
    fs::remove_all(dir_);
  }

  // A run of the smoke plan that stopped, as `rig sweep` leaves it after an abort.
  std::int64_t aborted_run(const nlohmann::json& extra_config = nlohmann::json::object()) {
    const std::int64_t run =
        store_->start_run(rig::sweep::describe_run(config_, config_.plan, extra_config));
    store_->finish_run(run, db::store::RunStatus::kAborted, "SIGINT received (after position 0)");
    return run;
  }

  // Calls `resume` expecting RunMismatch; returns its message.
  std::string resume_refusal(std::int64_t run) {
    try {
      rig::sweep::resume_run(config_, run, bench_, *store_, control_);
    } catch (const rig::sweep::RunMismatch& e) {
      return e.what();
    }
    ADD_FAILURE() << "run " << run << " was resumed";
    return "";
  }

  fs::path dir_;
  rig::sweep::SweepConfig config_;
  std::unique_ptr<db::store::Store> store_;
  CountingBench bench_;
  rig::telemetry::ControlState control_;
};

TEST_F(RunStartTest, ANewRunHomesAnUnhomedBenchBeforeTheRunIsRecorded) {
  std::size_t runs_while_homing = 99;
  bench_.on_home = [&] { runs_while_homing = store_->runs().size(); };
  const auto run = rig::sweep::start_new_run(config_, bench_, *store_, control_);
  ASSERT_TRUE(run.has_value());
  EXPECT_EQ(bench_.homes, 1);
  EXPECT_EQ(runs_while_homing, 0u);
  EXPECT_EQ(store_->run(run->run_id).status, db::store::RunStatus::kRunning);
  EXPECT_EQ(store_->run(run->run_id).description.plan_size,
            static_cast<std::int64_t>(config_.plan.size()));
  EXPECT_EQ(run->plan.to_json(), config_.plan.to_json());
}

TEST_F(RunStartTest, AHomedBenchIsNotHomedAgainNorAnyBenchWithoutHomeFirst) {
  bench_.homed = true;
  ASSERT_TRUE(rig::sweep::start_new_run(config_, bench_, *store_, control_));
  EXPECT_EQ(bench_.homes, 0);
  bench_.homed = false;
  config_.home_first = false;
  ASSERT_TRUE(rig::sweep::start_new_run(config_, bench_, *store_, control_));
  EXPECT_EQ(bench_.homes, 0);
  EXPECT_EQ(store_->runs().size(), 2u);
}

TEST_F(RunStartTest, AnAbortRequestedBeforeTheStartRecordsNothing) {
  bench_.on_home = [&] { control_.request_abort("SIGINT received"); };  // during homing
  EXPECT_FALSE(rig::sweep::start_new_run(config_, bench_, *store_, control_).has_value());
  EXPECT_TRUE(store_->runs().empty());

  const std::int64_t run = aborted_run();
  const std::size_t events = store_->events(run).size();
  EXPECT_FALSE(rig::sweep::resume_run(config_, run, bench_, *store_, control_).has_value());
  EXPECT_EQ(store_->run(run).status, db::store::RunStatus::kAborted);
  EXPECT_EQ(store_->events(run).size(), events);
}

TEST_F(RunStartTest, AResumeHomesThenPutsTheRunBackToRunningWithAResumeEvent) {
  const std::int64_t run = aborted_run();
  db::store::RunStatus status_while_homing = db::store::RunStatus::kRunning;
  bench_.on_home = [&] { status_while_homing = store_->run(run).status; };
  const auto resumed = rig::sweep::resume_run(config_, run, bench_, *store_, control_);
  ASSERT_TRUE(resumed.has_value());
  EXPECT_EQ(resumed->run_id, run);
  EXPECT_EQ(resumed->plan.to_json(), config_.plan.to_json());  // the stored plan
  EXPECT_EQ(bench_.homes, 1);
  EXPECT_EQ(status_while_homing, db::store::RunStatus::kAborted);
  EXPECT_EQ(store_->run(run).status, db::store::RunStatus::kRunning);
  const auto events = store_->events(run);
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.back().kind, "resume");
  EXPECT_EQ(events.back().message, "rig sweep --resume");
}

TEST_F(RunStartTest, AResumeIsRefusedBeforeTheBenchMovesForAnUnknownCompletedOrReplayRun) {
  EXPECT_EQ(resume_refusal(9).rfind("--resume 9: ", 0), 0u);

  const std::int64_t completed = store_->start_run(rig::sweep::describe_run(config_, config_.plan));
  store_->finish_run(completed, db::store::RunStatus::kCompleted, "");
  EXPECT_NE(resume_refusal(completed).find("is completed; there is nothing to resume"),
            std::string::npos);

  const std::int64_t replay = aborted_run({{"replay_of", {{"database", "a.db"}, {"run", 1}}}});
  EXPECT_NE(resume_refusal(replay).find("run " + std::to_string(replay) + " is a replay (of "),
            std::string::npos);
  EXPECT_EQ(bench_.homes, 0);
  EXPECT_EQ(store_->run(replay).status, db::store::RunStatus::kAborted);
}

// [capture] save_frames whose database folder is a symbolic link, or a file,
// is bad input found before the bench is homed, a new run recorded or a
// resumed one put back to running.
TEST_F(RunStartTest, AFramesFolderThatIsALinkOrAFileIsRefusedBeforeTheBenchMoves) {
  const std::int64_t stopped = aborted_run();
  config_.frames_dir = (dir_ / "frames").string();
  const fs::path folder = rig::sweep::database_frames_folder(*config_.frames_dir, store_->path());
  fs::create_directories(dir_ / "frames");
  fs::create_directories(dir_ / "elsewhere");
  for (const bool as_link : {true, false}) {
    fs::remove_all(folder);
    if (as_link)
      fs::create_directory_symlink(dir_ / "elsewhere", folder);
    else
      std::ofstream(folder) << "not a folder";
    const auto expect_refused = [&](const std::function<void()>& start) {
      try {
        start();
        ADD_FAILURE() << "started with " << folder;
      } catch (const rig::sweep::SweepConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("capture.save_frames = \"" + *config_.frames_dir),
                  std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find(folder.string()), std::string::npos) << e.what();
      }
    };
    expect_refused([&] { rig::sweep::start_new_run(config_, bench_, *store_, control_); });
    expect_refused([&] { rig::sweep::resume_run(config_, stopped, bench_, *store_, control_); });
  }
  EXPECT_EQ(bench_.homes, 0);
  EXPECT_EQ(store_->runs().size(), 1u);
  EXPECT_EQ(store_->run(stopped).status, db::store::RunStatus::kAborted);
  EXPECT_TRUE(fs::is_empty(dir_ / "elsewhere"));
}

TEST_F(RunStartTest, ADatabaseToReplayMustExist) {
  const std::string missing = (dir_ / "missing.db").string();
  try {
    rig::sweep::open_replay_database(missing, config_, 3);
    ADD_FAILURE() << "opened";
  } catch (const rig::sweep::RunMismatch& e) {
    EXPECT_EQ(std::string(e.what()),
              "--replay 3: database " + missing +
                  " does not exist; expected the database of the run to replay (--db)");
  }
  EXPECT_FALSE(fs::exists(missing));
}

TEST_F(RunStartTest, ARunDatabaseIsCreatedWithItsFolder) {
  const fs::path nested = dir_ / "out" / "ci" / "run.db";
  rig::sweep::open_run_database(nested.string(), config_);
  EXPECT_TRUE(fs::exists(nested));
}

TEST_F(RunStartTest, AReplayOfAnUnknownRunIsRefusedAndRecordsNothing) {
  try {
    rig::sweep::ReplayRun replay(config_, *store_, 9);
    ADD_FAILURE() << "replay of run 9 started as run " << replay.run_id();
  } catch (const rig::sweep::RunMismatch& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--replay 9: ", 0), 0u) << e.what();
  }
  EXPECT_TRUE(store_->runs().empty());
}

TEST_F(RunStartTest, AReplayRecordsANewRunNamingTheRecordedOneAndServesItsFrames) {
  // Run 1: one position at (400, 150) with one saved frame of the calibration's size.
  const rig::sweep::SweepPlan plan = rig::sweep::SweepPlan::from_json(
      {{"description", "one position"}, {"positions", {{400.0, 150.0}}}});
  const std::int64_t recorded = store_->start_run(rig::sweep::describe_run(config_, plan));
  const std::string png = (dir_ / "p0_f0.png").string();
  ASSERT_TRUE(vision::imwrite(png, cv::Mat(571, 736, CV_8UC1, cv::Scalar(77))));
  std::ifstream in(png, std::ios::binary);
  db::store::PositionRecord p;
  p.commanded_x_mm = p.measured_x_mm.emplace(400);
  p.commanded_y_mm = p.measured_y_mm.emplace(150);
  p.frames.resize(1);
  p.frames[0].image_path = png;
  p.frames[0].image_sha256 =
      db::store::sha256_hex(std::string(std::istreambuf_iterator<char>(in), {}));
  store_->append_position(recorded, p);
  store_->finish_run(recorded, db::store::RunStatus::kCompleted, "");

  config_.frames_per_position = 1;
  rig::sweep::ReplayRun replay(config_, *store_, recorded);
  EXPECT_NE(replay.run_id(), recorded);
  EXPECT_EQ(replay.recorded_run(), recorded);
  EXPECT_EQ(replay.plan().to_json(), plan.to_json());
  EXPECT_FALSE(replay.config().frames_dir.has_value());  // replay_config's
  const db::store::Run run = store_->run(replay.run_id());
  EXPECT_EQ(run.status, db::store::RunStatus::kRunning);
  EXPECT_EQ(
      nlohmann::json::parse(run.description.config_json)["replay_of"],
      nlohmann::json({{"database", fs::absolute(store_->path()).string()}, {"run", recorded}}));
  const auto events = store_->events(replay.run_id());
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, "start");
  EXPECT_EQ(events[0].message, "rig sweep --replay " + std::to_string(recorded));

  // The frames are open and serve the recorded position the bench moves to.
  replay.bench().move_to(400, 150);
  EXPECT_EQ(replay.bench().wait_settled(std::chrono::milliseconds(0)).position.x_mm, 400);
  const vision::Frame frame = replay.frames().grab(std::chrono::milliseconds(0));
  EXPECT_EQ(frame.origin, png);
  EXPECT_EQ(frame.image.at<unsigned char>(10, 10), 77);
}

}  // namespace
