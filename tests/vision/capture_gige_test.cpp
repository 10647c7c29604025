// GigeSource against a third-party camera: Aravis's own GigE Vision simulator
// `arv-fake-gv-camera-0.8` (Debian aravis-tools), run as a separate process
// on loopback. Its frames are a known diagonal ramp (arvfakecamera.c):
//   pixel(x, y) = clamp(((x + y + frame_id) mod 255) * scale),
//   scale = 1 + gain + log10(exposure_us / 10000),
// so each delivered frame can be checked whole, pixel for pixel, against the
// frame id it carries. Only one simulator can bind the GVCP port of an
// address, so these tests hold the ctest RESOURCE_LOCK gige_loopback.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "vision/frame_source.hpp"
#include "vision/gige_source.hpp"

extern char** environ;

namespace {

using namespace std::chrono_literals;

constexpr const char* kSerial = "RIGTEST";
constexpr const char* kAddress = "127.0.0.1";

// The simulator process, started with optional extra arguments and killed at
// the end of the test.
class FakeCameraProcess {
 public:
  explicit FakeCameraProcess(std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"arv-fake-gv-camera-0.8", "-i", kAddress, "-s", kSerial};
    args.insert(args.end(), extra.begin(), extra.end());
    std::vector<char*> argv;
    for (auto& a : args)
      argv.push_back(a.data());
    argv.push_back(nullptr);
    if (posix_spawnp(&pid_, argv[0], nullptr, nullptr, argv.data(), environ) != 0) pid_ = -1;
  }
  ~FakeCameraProcess() { kill(); }
  bool started() const { return pid_ > 0; }
  void kill() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }
  // Waits until the camera answers on its address (it binds within ~100 ms).
  bool wait_ready() {
    for (int i = 0; i < 50; ++i) {
      try {
        vision::GigeSource probe(kAddress);
        probe.open();
        return true;
      } catch (const vision::CaptureError&) {
        std::this_thread::sleep_for(50ms);
      }
    }
    return false;
  }

 private:
  pid_t pid_ = -1;
};

// Counts pixels that differ from the simulator's ramp for this frame.
int ramp_mismatches(const vision::Frame& frame, double scale) {
  int bad = 0;
  for (int y = 0; y < frame.image.rows; ++y)
    for (int x = 0; x < frame.image.cols; ++x) {
      const double expected =
          std::clamp(static_cast<double>((x + y + frame.frame_id) % 255) * scale, 0.0, 255.0);
      // The simulator truncates to an integer (C cast of CLAMP's double).
      if (frame.image.at<uint8_t>(y, x) != static_cast<uint8_t>(expected)) ++bad;
    }
  return bad;
}

class GigeFakeCamera : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(camera_.started()) << "arv-fake-gv-camera-0.8 not found (package aravis-tools)";
    ASSERT_TRUE(camera_.wait_ready()) << "arv-fake-gv-camera-0.8 did not answer on " << kAddress;
  }
  FakeCameraProcess camera_;
};

TEST_F(GigeFakeCamera, TriggeredFrameIsTheWholeRampAtTheRequestedRegion) {
  vision::CaptureOptions options;
  options.width = 736;
  options.height = 571;
  vision::GigeSource source(kAddress, options);
  source.open();
  source.trigger();
  const vision::Frame frame = source.grab(2000ms);
  EXPECT_EQ(frame.image.cols, 736);
  EXPECT_EQ(frame.image.rows, 571);
  EXPECT_EQ(frame.image.type(), CV_8UC1);
  EXPECT_EQ(ramp_mismatches(frame, 1.0), 0);
  EXPECT_GT(frame.camera_timestamp_ns, 0u);
  EXPECT_EQ(source.device_id(), std::string("Aravis-Fake-") + kSerial);
}

TEST_F(GigeFakeCamera, ExposureTimeReachesTheCamera) {
  // Doubling the exposure scales the ramp by 1 + log10(2) in the simulator.
  vision::CaptureOptions options;
  options.width = 64;
  options.height = 48;
  options.exposure_us = 20000;
  vision::GigeSource source(kAddress, options);
  source.open();
  source.trigger();
  EXPECT_EQ(ramp_mismatches(source.grab(2000ms), 1.0 + std::log10(2.0)), 0);
}

TEST_F(GigeFakeCamera, GainReachesTheCamera) {
  // The simulator has only GainRaw (integer); Aravis sets it for "gain", and a
  // gain of 1 doubles the ramp (scale = 1 + gain).
  vision::CaptureOptions options;
  options.width = 64;
  options.height = 48;
  options.gain = 1;
  vision::GigeSource source(kAddress, options);
  source.open();
  source.trigger();
  EXPECT_EQ(ramp_mismatches(source.grab(2000ms), 2.0), 0);
}

TEST_F(GigeFakeCamera, EachTriggerDeliversExactlyOneFrame) {
  vision::CaptureOptions options;
  options.width = 320;
  options.height = 240;
  vision::GigeSource source(kAddress, options);
  source.open();
  uint64_t previous = 0;
  for (int i = 0; i < 20; ++i) {
    source.trigger();
    const vision::Frame frame = source.grab(2000ms);
    if (i > 0 && previous != 65535) {
      EXPECT_EQ(frame.frame_id, previous + 1);
    }
    previous = frame.frame_id;
  }
  // Nothing more was exposed: a grab without a trigger times out.
  EXPECT_THROW(source.grab(300ms), vision::CaptureTimeout);
  const vision::CaptureCounters c = source.counters();
  EXPECT_EQ(c.delivered, 20u);
  EXPECT_EQ(c.lost, 0u);
  EXPECT_EQ(c.incomplete, 0u);
  EXPECT_EQ(c.discarded, 0u);
}

TEST_F(GigeFakeCamera, OpensByDeviceIdThroughDiscovery) {
  vision::GigeSource source(std::string("Aravis-Fake-") + kSerial);
  source.open();
  source.trigger();
  EXPECT_FALSE(source.grab(2000ms).image.empty());
}

TEST_F(GigeFakeCamera, FreeRunStreamsWithoutLostFrames) {
  vision::CaptureOptions options;
  options.software_trigger = false;
  options.frame_rate_hz = 200;
  options.width = 320;
  options.height = 240;
  vision::GigeSource source(kAddress, options);
  source.open();
  for (int i = 0; i < 100; ++i)
    EXPECT_EQ(ramp_mismatches(source.grab(1000ms), 1.0), 0);
  EXPECT_EQ(source.counters().lost, 0u);
  EXPECT_EQ(source.counters().incomplete, 0u);
}

TEST_F(GigeFakeCamera, CameraKilledMidStreamIsACaptureErrorNotAFrame) {
  vision::CaptureOptions options;
  options.width = 64;
  options.height = 48;
  options.retries = 1;
  vision::GigeSource source(kAddress, options);
  source.open();
  source.trigger();
  ASSERT_FALSE(source.grab(2000ms).image.empty());
  camera_.kill();
  try {
    source.trigger();
    source.grab(300ms);
    FAIL() << "a frame from a dead camera";
  } catch (const vision::CaptureError& e) {
    EXPECT_NE(std::string(e.what()).find("gige:127.0.0.1"), std::string::npos) << e.what();
  }
  EXPECT_EQ(source.counters().delivered, 1u);
}

TEST(GigeSource, AbsentCameraIsACaptureErrorNamingTheAddress) {
  // 127.0.0.2 is loopback too, but no camera listens there.
  vision::GigeSource source("127.0.0.2");
  try {
    source.open();
    FAIL() << "opened a camera that does not exist";
  } catch (const vision::CaptureError& e) {
    EXPECT_NE(std::string(e.what()).find("gige:127.0.0.2"), std::string::npos) << e.what();
  }
}

// With 2 % of packets dropped by the simulator and resend off, most frames of
// ~110 packets arrive incomplete. Every frame passed on must still be whole.
TEST(GigeLossyCamera, IncompleteFramesAreCountedAndNeverPassedOn) {
  FakeCameraProcess camera({"-r", "20"});
  ASSERT_TRUE(camera.started());
  ASSERT_TRUE(camera.wait_ready());
  vision::CaptureOptions options;
  options.width = 320;
  options.height = 480;
  options.packet_resend = false;
  options.retries = 50;
  vision::GigeSource source(kAddress, options);
  source.open();
  int whole = 0;
  for (int i = 0; i < 3; ++i) {
    source.trigger();
    try {
      EXPECT_EQ(ramp_mismatches(source.grab(1000ms), 1.0), 0);
      ++whole;
    } catch (const vision::CaptureError& e) {
      ADD_FAILURE() << "50 retries did not give one whole frame: " << e.what();
    }
  }
  EXPECT_EQ(whole, 3);
  EXPECT_GT(source.counters().incomplete, 0u);
  EXPECT_EQ(source.counters().retries, source.counters().incomplete + source.counters().timeouts);
}

}  // namespace
