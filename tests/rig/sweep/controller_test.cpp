// rig::sweep::Controller's fault handling, one fault at a time, with a scripted
// bench and camera in the test process (the real Modbus bench and GigE
// camera are exercised end to end in sweep_e2e_test.cpp). What matters here
// is what the controller decides: retake, fail the position, go on, abort,
// fail the run; and that the database says so.
#include "rig/sweep/controller.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <deque>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>

#include "db/store/store.hpp"
#include "motion/errors.hpp"
#include "rig/sweep/run_record.hpp"
#include "rig/sweep/sweep_config.hpp"

namespace {

using namespace std::chrono_literals;

// A bench that goes where it is told at once, unless a scripted fault says
// otherwise. `drift_mm` moves the read-back after a settle (a carriage that
// creeps during the exposures).
class ScriptedBench : public motion::Bench {
 public:
  std::deque<std::function<void()>> on_settle;  // run (and popped) at each wait_settled
  double drift_mm = 0;
  int settles = 0;

  void home() override {}
  void move_to(double x_mm, double y_mm) override { at_ = {x_mm, y_mm}; }
  motion::BenchStatus wait_settled(std::chrono::milliseconds) override {
    ++settles;
    if (!on_settle.empty()) {
      auto fault = on_settle.front();
      on_settle.pop_front();
      fault();
    }
    motion::BenchStatus s;
    s.position = at_;
    s.homed = s.in_position = true;
    settled_ = at_;
    return s;
  }
  std::deque<std::function<void()>> on_position;  // run (and popped) at each position()
  motion::XY position() override {
    if (!on_position.empty()) {
      auto fault = on_position.front();
      on_position.pop_front();
      fault();
    }
    return {settled_.x_mm + drift_mm, settled_.y_mm};
  }
  // The state as it stands; scripted faults belong to wait_settled alone.
  motion::BenchStatus status() override {
    motion::BenchStatus s;
    s.position = at_;
    s.homed = s.in_position = true;
    return s;
  }
  void stop() override {}
  void reset_alarm() override {}

 private:
  motion::XY at_, settled_;
};

// A camera that delivers grey frames of the calibration's size, or throws
// what the script says.
class ScriptedCamera : public vision::FrameSource {
 public:
  std::deque<std::function<void()>> on_grab;
  bool stale = false;  // deliver frames stamped before the trigger
  int grabs = 0;
  int opens = 0, closes = 0;

  void open() override { ++opens; }
  void trigger() override { triggered_ = std::chrono::system_clock::now(); }
  vision::Frame grab(std::chrono::milliseconds) override {
    ++grabs;
    if (!on_grab.empty()) {
      auto fault = on_grab.front();
      on_grab.pop_front();
      fault();
    }
    vision::Frame f;
    f.image = cv::Mat(571, 736, CV_8UC1, cv::Scalar(128));
    f.host_time = stale ? triggered_ - std::chrono::seconds(1) : std::chrono::system_clock::now();
    return f;
  }
  void close() override { ++closes; }
  std::string name() const override { return "scripted"; }
  vision::CaptureCounters counters() const override { return {}; }

 private:
  std::chrono::system_clock::time_point triggered_;
};

class ControllerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("rig_controller_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    config_ =
        rig::sweep::load_sweep_config(std::string(RIG_SOURCE_DIR) + "/config/sweeps/smoke.toml");
    config_.frames_per_position = 2;
    config_.capture.retries = 1;
    config_.faults.max_consecutive_failed_positions = 3;
    config_.faults.link_retries = 1;
    store_ = std::make_unique<db::store::Store>((dir_ / "run.db").string());
    run_ = store_->start_run(rig::sweep::describe_run(config_, config_.plan));
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  rig::sweep::RunOutcome sweep() {
    rig::sweep::Controller controller(config_, config_.plan, bench_, camera_, *store_, run_,
                                      control_, nullptr);
    return controller.run();
  }
  db::store::PositionRecord stored(std::int64_t index) { return store_->position(run_, index); }

  std::filesystem::path dir_;
  rig::sweep::SweepConfig config_;
  std::unique_ptr<db::store::Store> store_;
  std::int64_t run_ = 0;
  ScriptedBench bench_;
  ScriptedCamera camera_;
  rig::telemetry::ControlState control_;
};

TEST_F(ControllerTest, MeasuresEveryPositionWithItsFramesAndCompletes) {
  const rig::sweep::RunOutcome outcome = sweep();
  EXPECT_EQ(outcome.status, db::store::RunStatus::kCompleted);
  EXPECT_EQ(outcome.positions_ok, static_cast<std::int64_t>(config_.plan.size()));
  EXPECT_EQ(stored(0).frames.size(), 2u);
  EXPECT_EQ(store_->run(run_).status, db::store::RunStatus::kCompleted);
}

TEST_F(ControllerTest, ASettleTimeoutFailsThePositionAndTheSweepGoesOn) {
  bench_.on_settle.push_back([] { throw motion::BenchTimeout("bench: not settled within 25 s"); });
  const rig::sweep::RunOutcome outcome = sweep();
  EXPECT_EQ(outcome.status, db::store::RunStatus::kCompleted);
  EXPECT_EQ(outcome.positions_failed, 1);
  EXPECT_EQ(stored(0).status, db::store::PositionStatus::kFailed);
  EXPECT_NE(stored(0).failure_reason.find("not settled"), std::string::npos);
  EXPECT_TRUE(stored(0).frames.empty());
  EXPECT_EQ(stored(1).status, db::store::PositionStatus::kOk);
}

TEST_F(ControllerTest, ACameraTimeoutFailsThePositionAndIsRecordedWhenReopeningIsOff) {
  config_.faults.camera_reopen_timeout = std::chrono::milliseconds(0);
  camera_.on_grab.push_back(
      [] { throw vision::CaptureTimeout("scripted", "no frame in 2000 ms"); });
  EXPECT_EQ(sweep().positions_failed, 1);
  EXPECT_EQ(camera_.closes, 0);
  EXPECT_EQ(stored(0).failure_reason, "camera: scripted: no frame in 2000 ms");
  const auto events = store_->events(run_);
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.front().kind, "camera");
  EXPECT_EQ(events.front().plan_index, 0);
}

// A camera that fails at a position is closed and opened again, checked with
// one frame, and the position's frames are taken again: the position is ok.
TEST_F(ControllerTest, ALostCameraIsReopenedAndThePositionsFramesAreTakenAgain) {
  camera_.on_grab.push_back(
      [] { throw vision::CaptureError("scripted", "control of the camera lost"); });
  const rig::sweep::RunOutcome outcome = sweep();
  EXPECT_EQ(outcome.status, db::store::RunStatus::kCompleted);
  EXPECT_EQ(outcome.positions_failed, 0);
  EXPECT_EQ(stored(0).status, db::store::PositionStatus::kOk);
  EXPECT_EQ(stored(0).frames.size(), 2u);
  EXPECT_EQ(camera_.closes, 1);
  EXPECT_EQ(camera_.opens, 1);
  // The failed grab, the check frame of the reopened camera, then the 2 frames
  // of position 0 again, then 2 per other position.
  EXPECT_EQ(camera_.grabs, 1 + 1 + 2 * static_cast<int>(config_.plan.size()));
  const auto events = store_->events(run_);
  ASSERT_GE(events.size(), 2u);
  EXPECT_EQ(events[0].kind, "camera");
  EXPECT_EQ(events[0].message, "scripted: control of the camera lost (reopen)");
  EXPECT_EQ(events[1].kind, "camera");
  EXPECT_EQ(events[1].message.rfind("reopened at attempt 1, ", 0), 0u) << events[1].message;
}

// A camera that does not come back within camera_reopen_timeout fails the
// position, saying so, and the sweep goes on.
TEST_F(ControllerTest, ACameraThatDoesNotComeBackInTimeFailsThePosition) {
  config_.faults.camera_reopen_timeout = std::chrono::milliseconds(30);
  config_.faults.camera_reopen_interval = std::chrono::milliseconds(10);
  // The loss, then the check frame of every reopening attempt fails (about
  // 3 within 30 ms at 10 ms apart; 40 failures outlast them), then the
  // camera works.
  for (int i = 0; i < 40; ++i)
    camera_.on_grab.push_back([] { throw vision::CaptureTimeout("scripted", "no frame"); });
  const rig::sweep::RunOutcome outcome = sweep();
  EXPECT_GE(outcome.positions_failed, 1);
  const std::string reason = stored(0).failure_reason;
  EXPECT_EQ(reason.rfind("camera: scripted: no frame; not reopened within "
                         "faults.camera_reopen_timeout_ms = 30 (",
                         0),
            0u)
      << reason;
  EXPECT_NE(reason.find(" attempts; last: scripted: no frame)"), std::string::npos) << reason;
  // At least one attempt, however the host schedules the 10 ms waits.
  EXPECT_GE(camera_.opens, 1);
}

TEST_F(ControllerTest, FramesExposedBeforeTheBenchSettledAreNeverKept) {
  camera_.stale = true;  // every frame predates the trigger, hence the settle
  const rig::sweep::RunOutcome outcome = sweep();
  // Discarded, retried capture_retries times, then the position fails;
  // three such positions in a row abort the run.
  EXPECT_EQ(outcome.status, db::store::RunStatus::kAborted);
  EXPECT_EQ(outcome.positions_failed, 3);
  EXPECT_NE(stored(0).failure_reason.find("exposed before the bench settled"), std::string::npos);
  EXPECT_EQ(camera_.grabs, 3 * (1 + config_.capture.retries));
}

TEST_F(ControllerTest, ABenchThatMovedDuringTheExposuresHasItsFramesRetakenThenFails) {
  // Creeping by twice the tolerance after every settle: the frames are taken
  // again (capture_retries times) and the position then fails.
  bench_.drift_mm = 2 * config_.bench_profile.position_tolerance_mm;
  config_.faults.max_consecutive_failed_positions = 1;
  const rig::sweep::RunOutcome outcome = sweep();
  EXPECT_EQ(outcome.status, db::store::RunStatus::kAborted);
  EXPECT_EQ(bench_.settles, 1 + config_.capture.retries);
  EXPECT_NE(stored(0).failure_reason.find("moved"), std::string::npos);
}

TEST_F(ControllerTest, ALinkDropIsRetriedThenFailsTheRunResumably) {
  for (int i = 0; i < 2; ++i)
    bench_.on_settle.push_back([] { throw motion::BenchLinkError("bench: link lost"); });
  const rig::sweep::RunOutcome outcome = sweep();
  // One retry allowed (link_retries = 1): the second drop fails the run.
  EXPECT_EQ(outcome.status, db::store::RunStatus::kFailed);
  EXPECT_NE(outcome.reason.find("link lost"), std::string::npos);
  EXPECT_EQ(store_->first_incomplete_position(run_), 0);
  store_->resume_run(run_);  // and it can be resumed
}

TEST_F(ControllerTest, ALinkDropWithinTheRetriesIsRiddenOut) {
  bench_.on_settle.push_back([] { throw motion::BenchLinkError("bench: link lost"); });
  const rig::sweep::RunOutcome outcome = sweep();
  EXPECT_EQ(outcome.status, db::store::RunStatus::kCompleted);
  EXPECT_EQ(outcome.positions_failed, 0);
}

TEST_F(ControllerTest, AnAbortRequestFinishesThePositionThenEndsTheRunAborted) {
  bench_.on_settle.push_back([this] { control_.request_abort("SIGTERM received"); });
  const rig::sweep::RunOutcome outcome = sweep();
  EXPECT_EQ(outcome.status, db::store::RunStatus::kAborted);
  EXPECT_EQ(outcome.positions_ok, 1);  // the one in progress was finished and stored
  EXPECT_NE(store_->run(run_).status_reason.find("SIGTERM"), std::string::npos);
}

TEST_F(ControllerTest, AResumedRunMeasuresOnlyWhatIsMissing) {
  bench_.on_settle.push_back([this] { control_.request_abort("stop"); });
  sweep();
  store_->resume_run(run_);
  rig::telemetry::ControlState fresh;
  rig::sweep::Controller controller(config_, config_.plan, bench_, camera_, *store_, run_, fresh,
                                    nullptr);
  const rig::sweep::RunOutcome outcome = controller.run();
  EXPECT_EQ(outcome.status, db::store::RunStatus::kCompleted);
  EXPECT_EQ(outcome.positions_ok, static_cast<std::int64_t>(config_.plan.size()) - 1);
  EXPECT_EQ(outcome.stored_total, static_cast<std::int64_t>(config_.plan.size()));
}

}  // namespace

namespace {

TEST_F(ControllerTest, AResumeRefusesAFileThatChangedSinceTheRunStarted) {
  bench_.on_settle.push_back([this] { control_.request_abort("stop"); });
  sweep();
  const db::store::Run run = store_->run(run_);
  // Unchanged files: the stored plan comes back.
  EXPECT_EQ(rig::sweep::plan_for_resume(run, config_).size(), config_.plan.size());
  // The drive profile is now another file: the run would be measured with
  // something other than what it started with.
  config_.bench_profile_path = std::string(RIG_SOURCE_DIR) + "/tests/motion/pymodbus_drive.toml";
  try {
    rig::sweep::plan_for_resume(run, config_);
    FAIL() << "resumed with a changed file";
  } catch (const rig::sweep::RunMismatch& e) {
    EXPECT_NE(
        std::string(e.what()).find("pymodbus_drive.toml differs from the copy the run stored"),
        std::string::npos)
        << e.what();
  }
}

}  // namespace

namespace {

TEST_F(ControllerTest, ABenchAlarmEndsTheRunAbortedWhenThePolicySaysAbort) {
  config_.faults.on_alarm = rig::sweep::AlarmAction::kAbort;
  bench_.on_settle.push_back(
      [] { throw motion::BenchFault("bench: alarm 2", 2, "following error"); });
  const rig::sweep::RunOutcome outcome = sweep();
  EXPECT_EQ(outcome.status, db::store::RunStatus::kAborted);
  EXPECT_NE(outcome.reason.find("bench alarm"), std::string::npos);
  EXPECT_EQ(outcome.stored_total, 0);
  EXPECT_EQ(store_->events(run_).front().kind, "alarm");
}

TEST_F(ControllerTest, ABenchAlarmPausesUntilResumedThenRetriesThePosition) {
  config_.faults.on_alarm = rig::sweep::AlarmAction::kPause;
  bench_.on_settle.push_back(
      [] { throw motion::BenchFault("bench: alarm 2", 2, "following error"); });
  // The operator: resumes once the controller is holding.
  std::thread operator_thread([this] {
    while (!control_.paused())
      std::this_thread::sleep_for(1ms);
    control_.request_resume();
  });
  const rig::sweep::RunOutcome outcome = sweep();
  operator_thread.join();
  EXPECT_EQ(outcome.status, db::store::RunStatus::kCompleted);
  EXPECT_EQ(outcome.positions_failed, 0);
  EXPECT_EQ(bench_.settles, static_cast<int>(config_.plan.size()) + 1);  // position 0 twice
  std::vector<std::string> kinds;
  for (const auto& e : store_->events(run_))
    kinds.push_back(e.kind);
  EXPECT_EQ(kinds, (std::vector<std::string>{"alarm", "pause", "resume"}));
}

TEST_F(ControllerTest, AReadBackThatFailsAfterTheExposuresHasTheFramesRetaken) {
  bench_.on_position.push_back([] { throw motion::BenchLinkError("bench: link lost"); });
  const rig::sweep::RunOutcome outcome = sweep();
  EXPECT_EQ(outcome.status, db::store::RunStatus::kCompleted);
  EXPECT_EQ(outcome.positions_failed, 0);
  EXPECT_EQ(camera_.grabs, 2 * (static_cast<int>(config_.plan.size()) + 1));
}

TEST_F(ControllerTest, ADatabaseThatRefusesAPositionFailsTheRunAndTheErrorReachesTheCaller) {
  // Someone ends the run behind the controller's back: the next append is refused.
  bench_.on_settle.push_back(
      [this] { store_->finish_run(run_, db::store::RunStatus::kAborted, "ended elsewhere"); });
  EXPECT_THROW(sweep(), db::store::StoreError);
  EXPECT_TRUE(store_->completed_position_indices(run_).empty());
}

}  // namespace
