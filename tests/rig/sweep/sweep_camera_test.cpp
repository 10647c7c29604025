// Opening a sweep's camera (rig/sweep/sweep_camera.hpp): the held-camera
// retry policy and the one-frame check against the calibration, with scripted
// frame sources (the real GigE Vision source is exercised end to end in
// sweep_e2e_test.cpp and in the vision tests).
#include "rig/sweep/sweep_camera.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <deque>
#include <functional>
#include <string>

namespace {

using namespace std::chrono_literals;

// What one attempt's source does when opened: throw, or open and then
// deliver frames of `size`.
struct Script {
  std::function<void()> on_open;  // empty: opens
  cv::Size size{736, 571};
};

class ScriptedSource : public vision::FrameSource {
 public:
  explicit ScriptedSource(Script script) : script_(std::move(script)) {}
  void open() override {
    if (script_.on_open) script_.on_open();
  }
  void trigger() override {}
  vision::Frame grab(std::chrono::milliseconds) override {
    vision::Frame f;
    f.image = cv::Mat(script_.size, CV_8UC1, cv::Scalar(0));
    f.host_time = std::chrono::system_clock::now();
    return f;
  }
  void close() override {}
  std::string name() const override { return "scripted"; }
  vision::CaptureCounters counters() const override { return {}; }

 private:
  Script script_;
};

class SweepCameraTest : public ::testing::Test {
 protected:
  void SetUp() override {
    config_ = rig::sweep::load_sweep_config(std::string(RIG_SOURCE_DIR) +
                                            "/config/sweeps/smoke.toml");  // the paper camera
  }

  // Opens under `policy` with one script per attempt (the last repeats).
  std::unique_ptr<vision::FrameSource> open(const rig::sweep::HeldCameraPolicy& policy) {
    return rig::sweep::open_sweep_camera(
        config_,
        [this] {
          ++attempts_;
          const Script s = scripts_.front();
          if (scripts_.size() > 1) scripts_.pop_front();
          return std::make_unique<ScriptedSource>(s);
        },
        policy, [this](int attempt, const vision::CaptureError&) { retries_.push_back(attempt); });
  }

  static Script refused() {
    return {[] { throw vision::CaptureError("gige:127.0.0.1", "AcquisitionMode refused: busy"); }};
  }

  rig::sweep::SweepConfig config_;
  std::deque<Script> scripts_;
  int attempts_ = 0;
  std::vector<int> retries_;
};

TEST(CameraMayBeHeld, TimeoutsAndRefusalsAreWorthAskingAgainAnAbsentCameraIsNot) {
  EXPECT_TRUE(rig::sweep::camera_may_be_held(vision::CaptureTimeout("gige:x", "no frame")));
  EXPECT_TRUE(
      rig::sweep::camera_may_be_held(vision::CaptureError("gige:x", "PixelFormat refused: busy")));
  EXPECT_TRUE(rig::sweep::camera_may_be_held(
      vision::CaptureControlLost("gige:x", "control of the camera lost")));
  EXPECT_FALSE(rig::sweep::camera_may_be_held(
      vision::CaptureError("gige:x", "no GigE Vision camera answers (timeout)")));
}

TEST_F(SweepCameraTest, ACameraThatTookControlAwayIsAskedAgain) {
  scripts_ = {{[] { throw vision::CaptureControlLost("gige:127.0.0.1", "control lost"); }},
              Script{}};
  EXPECT_NE(open({10s, 1ms}), nullptr);
  EXPECT_EQ(attempts_, 2);
  EXPECT_EQ(retries_, (std::vector<int>{1}));
}

TEST_F(SweepCameraTest, AHeldCameraIsAskedAgainUntilItAnswers) {
  scripts_ = {refused(), refused(), Script{}};
  const auto camera = open({10s, 1ms});  // patience far beyond three attempts
  EXPECT_NE(camera, nullptr);
  EXPECT_EQ(attempts_, 3);
  EXPECT_EQ(retries_, (std::vector<int>{1, 2}));
}

TEST_F(SweepCameraTest, AnAbsentCameraIsReportedAtOnce) {
  scripts_ = {
      {[] { throw vision::CaptureError("gige:127.0.0.1", "no GigE Vision camera answers"); }}};
  EXPECT_THROW(open({10s, 1ms}), vision::CaptureError);
  EXPECT_EQ(attempts_, 1);
  EXPECT_TRUE(retries_.empty());
}

TEST_F(SweepCameraTest, ACameraStillHeldAfterThePatienceIsReported) {
  scripts_ = {refused()};
  // No patience: the first failure is past the deadline, unless the clock
  // has not advanced at all since the start, which allows one more attempt.
  EXPECT_THROW(open({0ms, 1ms}), vision::CaptureError);
  EXPECT_GE(attempts_, 1);
  EXPECT_LE(attempts_, 2);
}

TEST_F(SweepCameraTest, AFrameOfAnotherSizeThanTheCalibrationStopsAtOnce) {
  scripts_ = {Script{{}, {640, 480}}};
  try {
    open({10s, 1ms});
    ADD_FAILURE() << "opened";
  } catch (const rig::sweep::SweepConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              config_.sweep_file +
                  ": capture.calibration: the built-in paper camera (capture.calibration = \"\") "
                  "is for 736x571 px but a frame of camera gige:127.0.0.1 is 640x480 px; expected "
                  "the calibration of this camera at this resolution");
  }
  EXPECT_EQ(attempts_, 1);
}

}  // namespace
