// rig::estimator::ExternalEstimator against real processes: the scripted
// estimator (scripted_estimator.py) done right and each failure mode, and the
// restart policy. Every wait is bounded by the spec's timeouts, which are
// far above what a healthy answer takes (a Python process answers a frame in
// well under 10 ms) and far below what a hang takes (an hour), so no outcome
// depends on the machine's speed.
#include "rig/estimator/external_estimator.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "vision/camera.hpp"
#include "vision/target.hpp"

namespace {

using rig::estimator::EstimatorSpec;
using rig::estimator::ExternalEstimator;
using rig::estimator::FailureKind;
using rig::estimator::FrameRequest;
using rig::estimator::FrameResult;

const std::string kScript =
    std::string(RIG_SOURCE_DIR) + "/tests/rig/estimator/scripted_estimator.py";

vision::Target paper_target() {
  return vision::Target::load(std::string(RIG_SOURCE_DIR) + "/config/targets/paper.toml");
}

EstimatorSpec spec(const std::vector<std::string>& args, int max_restarts = 3) {
  EstimatorSpec s;
  s.name = "scripted";
  s.command = {"python3", kScript};
  s.command.insert(s.command.end(), args.begin(), args.end());
  s.timeout = std::chrono::milliseconds(1500);
  s.startup_timeout = std::chrono::milliseconds(5000);
  s.max_restarts = max_restarts;
  return s;
}

class ExternalEstimatorTest : public ::testing::Test {
 protected:
  FrameResult ask(ExternalEstimator& e) {
    FrameRequest request;
    request.image_path = "/nonexistent/frame.png";  // the scripted estimator does not read it
    return e.estimate(request);
  }
  std::string once_file() const {
    return (std::filesystem::temp_directory_path() /
            ("rig_estimator_once_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name()))
        .string();
  }
  void TearDown() override { std::filesystem::remove(once_file()); }
  const vision::Camera camera_ = vision::Camera::paper_default();
  const vision::Target target_ = paper_target();
};

TEST_F(ExternalEstimatorTest, HandshakeThenOnePosePerFrame) {
  ExternalEstimator e(spec({"ok"}), camera_, target_);
  EXPECT_FALSE(e.start());
  EXPECT_EQ(e.reported_name(), "scripted-ok");
  EXPECT_EQ(e.reported_version(), "0.1");
  for (int k = 0; k < 3; ++k) {
    const FrameResult r = ask(e);
    ASSERT_FALSE(r.failure) << r.failure->reason;
    ASSERT_EQ(r.poses.size(), 1u);
    EXPECT_EQ(r.poses[0].scope, "target");
    EXPECT_DOUBLE_EQ(r.poses[0].T_cam_target.t.z(), 1.0);
    EXPECT_EQ(r.estimator_time_us, 5.0);
    EXPECT_GT(r.round_trip_us, 0);
  }
  const auto events = e.take_events();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_NE(events[0].message.find("scripted-ok 0.1, protocol rig-estimator 1"), std::string::npos)
      << events[0].message;
}

TEST_F(ExternalEstimatorTest, WrongProtocolVersionIsRefusedAndDisablesAtOnce) {
  ExternalEstimator e(spec({"wrong_version"}), camera_, target_);
  const auto f = e.start();
  ASSERT_TRUE(f);
  EXPECT_EQ(f->kind, FailureKind::kProtocol);
  EXPECT_NE(f->reason.find("it speaks protocol \"rig-estimator\" version 99; rig speaks "
                           "\"rig-estimator\" version 1"),
            std::string::npos)
      << f->reason;
  EXPECT_TRUE(e.disabled());
  const FrameResult r = ask(e);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->kind, FailureKind::kDisabled);
  EXPECT_NE(r.failure->reason.find("version 99"), std::string::npos) << r.failure->reason;
  EXPECT_EQ(e.restarts(), 0);
}

TEST_F(ExternalEstimatorTest, CrashIsContainedAndTheRestartedProcessAnswers) {
  ExternalEstimator e(spec({"crash", "--once", once_file()}), camera_, target_);
  ASSERT_FALSE(e.start());
  const FrameResult crashed = ask(e);
  ASSERT_TRUE(crashed.failure);
  EXPECT_EQ(crashed.failure->kind, FailureKind::kCrash);
  EXPECT_NE(crashed.failure->reason.find("exited with status 3"), std::string::npos)
      << crashed.failure->reason;
  EXPECT_FALSE(e.running());
  const FrameResult next = ask(e);
  ASSERT_FALSE(next.failure) << next.failure->reason;
  EXPECT_EQ(next.poses.size(), 1u);
  EXPECT_EQ(e.restarts(), 1);
}

TEST_F(ExternalEstimatorTest, SegfaultNamesTheSignal) {
  ExternalEstimator e(spec({"segfault", "--once", once_file()}), camera_, target_);
  const FrameResult r = ask(e);  // started on the first frame
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->kind, FailureKind::kCrash);
  EXPECT_NE(r.failure->reason.find("killed by signal 11"), std::string::npos) << r.failure->reason;
  EXPECT_FALSE(ask(e).failure);
}

TEST_F(ExternalEstimatorTest, HangTimesOutWithinTheFrameTimeoutAndIsKilled) {
  ExternalEstimator e(spec({"hang", "--once", once_file()}), camera_, target_);
  ASSERT_FALSE(e.start());
  const auto start = std::chrono::steady_clock::now();
  const FrameResult r = ask(e);
  const auto waited = std::chrono::steady_clock::now() - start;
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->kind, FailureKind::kTimeout);
  EXPECT_NE(r.failure->reason.find("1500 ms, timeout_ms"), std::string::npos) << r.failure->reason;
  // At least the timeout; at most the timeout plus the kill and reap, which
  // take milliseconds (the bound leaves 1.5 s for a loaded machine).
  EXPECT_GE(waited, std::chrono::milliseconds(1500));
  EXPECT_LT(waited, std::chrono::milliseconds(3000));
  EXPECT_FALSE(ask(e).failure);
}

TEST_F(ExternalEstimatorTest, WhatAHungEstimatorStartedIsKilledWithIt) {
  const std::string pid_file = once_file() + ".pid";
  ExternalEstimator e(spec({"orphan", "--pid", pid_file}), camera_, target_);
  const FrameResult r = ask(e);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->kind, FailureKind::kTimeout);
  std::ifstream in(pid_file);
  pid_t sleeper = 0;
  ASSERT_TRUE(in >> sleeper);
  std::filesystem::remove(pid_file);
  // SIGKILL went to its process group: the orphan is dead at once, a zombie
  // until init (or a subreaper) reaps it, which a container's init may never
  // do; dead or zombie is gone. 5 s is generous for the signal on a loaded
  // machine.
  const auto dead = [](pid_t pid) {
    if (::kill(pid, 0) == -1 && errno == ESRCH) return true;
    std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
    std::string pid_text, comm, state;
    return stat >> pid_text >> comm >> state && state == "Z";
  };
  bool gone = false;
  for (int i = 0; i < 500 && !gone; ++i) {
    gone = dead(sleeper);
    if (!gone) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (!gone) ::kill(sleeper, SIGKILL);
  EXPECT_TRUE(gone) << "pid " << sleeper << " outlived its estimator";
}

TEST_F(ExternalEstimatorTest, MalformedAnswersAreFailuresNamingTheField) {
  {
    ExternalEstimator e(spec({"malformed", "--once", once_file()}), camera_, target_);
    const FrameResult r = ask(e);
    ASSERT_TRUE(r.failure);
    EXPECT_EQ(r.failure->kind, FailureKind::kMalformed);
    EXPECT_NE(r.failure->reason.find("the estimator's answer"), std::string::npos)
        << r.failure->reason;
    EXPECT_FALSE(ask(e).failure);
  }
  std::filesystem::remove(once_file());
  ExternalEstimator e(spec({"bad_rotation", "--once", once_file()}), camera_, target_);
  const FrameResult r = ask(e);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->kind, FailureKind::kMalformed);
  EXPECT_NE(r.failure->reason.find("poses[0].R = [[2,0,0],[0,1,0],[0,0,1]]; expected a rotation"),
            std::string::npos)
      << r.failure->reason;
}

TEST_F(ExternalEstimatorTest, SilentStartTimesOutAtTheStartupTimeout) {
  EstimatorSpec s = spec({"silent_start"}, 0);
  s.startup_timeout = std::chrono::milliseconds(800);
  ExternalEstimator e(s, camera_, target_);
  const auto f = e.start();
  ASSERT_TRUE(f);
  EXPECT_EQ(f->kind, FailureKind::kStart);
  EXPECT_NE(f->reason.find("800 ms, startup_timeout_ms"), std::string::npos) << f->reason;
  EXPECT_TRUE(e.disabled());  // max_restarts = 0
}

TEST_F(ExternalEstimatorTest, AProgramThatDoesNotExistIsAStartFailure) {
  EstimatorSpec s = spec({}, 0);
  s.command = {"/nonexistent/estimator"};
  ExternalEstimator e(s, camera_, target_);
  const auto f = e.start();
  ASSERT_TRUE(f);
  EXPECT_EQ(f->kind, FailureKind::kStart);
  EXPECT_NE(f->reason.find("/nonexistent/estimator"), std::string::npos) << f->reason;
}

TEST_F(ExternalEstimatorTest, DeclinedFrameKeepsTheProcess) {
  ExternalEstimator e(spec({"decline"}), camera_, target_);
  const FrameResult r = ask(e);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->kind, FailureKind::kDeclined);
  EXPECT_EQ(r.failure->reason, "frame 0: no markers I trust");
  EXPECT_TRUE(e.running());
  EXPECT_FALSE(ask(e).failure);
  EXPECT_EQ(e.restarts(), 0);
}

TEST_F(ExternalEstimatorTest, AfterMaxRestartsItIsDisabledWithTheLastReason) {
  ExternalEstimator e(spec({"crash"}, 2), camera_, target_);
  for (int k = 0; k < 3; ++k) {  // the first start and two restarts, each crashing
    const FrameResult r = ask(e);
    ASSERT_TRUE(r.failure);
    EXPECT_EQ(r.failure->kind, FailureKind::kCrash) << k;
  }
  EXPECT_TRUE(e.disabled());
  EXPECT_EQ(e.restarts(), 2);
  const FrameResult r = ask(e);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.failure->kind, FailureKind::kDisabled);
  EXPECT_NE(r.failure->reason.find("failed after 2 restarts (max_restarts); last: crash"),
            std::string::npos)
      << r.failure->reason;
  bool logged_disabled = false;
  for (const auto& event : e.take_events())
    logged_disabled |=
        event.message.find("disabled for the rest of the sweep") != std::string::npos;
  EXPECT_TRUE(logged_disabled);
}

TEST_F(ExternalEstimatorTest, RigsCornersAreSentUnlessSendCornersIsOff) {
  std::vector<vision::Detection> detections(2);
  detections[0].id = 0;
  detections[1].id = 3;
  FrameRequest request;
  request.image_path = "/nonexistent/frame.png";
  request.detections = &detections;
  ExternalEstimator with(spec({"echo_detections"}), camera_, target_);
  const FrameResult r = with.estimate(request);
  ASSERT_FALSE(r.failure) << r.failure->reason;
  ASSERT_EQ(r.poses.size(), 2u);
  EXPECT_EQ(r.poses[0].scope, "0");
  EXPECT_EQ(r.poses[1].scope, "3");
  EstimatorSpec without_corners = spec({"echo_detections"});
  without_corners.send_corners = false;
  ExternalEstimator without(without_corners, camera_, target_);
  const FrameResult none = without.estimate(request);
  ASSERT_FALSE(none.failure) << none.failure->reason;
  EXPECT_TRUE(none.poses.empty());
}

TEST(EstimatorProtocol, CameraAndTargetAreSentWithUnits) {
  const auto camera =
      nlohmann::json::parse(rig::estimator::camera_json(vision::Camera::paper_default()));
  EXPECT_EQ(camera["width_px"], 736);
  EXPECT_EQ(camera["height_px"], 571);
  EXPECT_DOUBLE_EQ(camera["K"][0][0].get<double>(), 706.1);
  EXPECT_DOUBLE_EQ(camera["distortion"][0].get<double>(), -0.2279);
  const vision::Target target = paper_target();
  const auto t = nlohmann::json::parse(rig::estimator::target_json(target));
  EXPECT_EQ(t["pose_marker"], target.pose_marker_id);
  ASSERT_EQ(t["markers"].size(), target.markers.size());
  const auto corners = target.corners_m(target.markers[0]);
  EXPECT_DOUBLE_EQ(t["markers"][0]["corners_m"][2][0].get<double>(), corners[2].x());
  EXPECT_DOUBLE_EQ(t["markers"][0]["side_m"].get<double>(), target.markers[0].side_m);
}

}  // namespace
