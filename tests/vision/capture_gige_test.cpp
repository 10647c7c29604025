// GigeSource against a third-party camera: Aravis's own GigE Vision simulator
// `arv-fake-gv-camera-0.8` (Debian aravis-tools), run as a separate process
// on loopback. Its frames are a known diagonal ramp (arvfakecamera.c):
//   pixel(x, y) = clamp(((x + y + frame_id) mod 255) * scale),
//   scale = 1 + gain + log10(exposure_us / 10000),
// so each delivered frame can be checked whole, pixel for pixel, against the
// frame id it carries. Only one simulator can bind the GVCP port of an
// address, so these tests hold the ctest RESOURCE_LOCK gige_loopback.
//
// Waits: a triggered frame arrives within milliseconds, so a grab that
// expects a frame waits kFrameWait, which only bounds a broken test and
// leaves orders of magnitude for a loaded host or a sanitizer build (a grab
// returns as soon as its frame is there). A grab that expects no frame waits
// a short time: it can only pass wrongly, never fail wrongly, on a slow host.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "camera_frames.hpp"
#include "gvsp_loss_relay.hpp"
#include "vision/frame_source.hpp"
#include "vision/gige_source.hpp"

extern char** environ;

namespace {

using rig_test::kFrameWait;

using namespace std::chrono_literals;

constexpr const char* kSerial = "RIGTEST";
constexpr const char* kAddress = "127.0.0.1";

// The simulator process, started at kAddress and killed at the end of the test.
class FakeCameraProcess {
 public:
  FakeCameraProcess() {
    std::vector<std::string> args = {"arv-fake-gv-camera-0.8", "-i", kAddress, "-s", kSerial};
    std::vector<char*> argv;
    for (auto& a : args)
      argv.push_back(a.data());
    argv.push_back(nullptr);
    if (posix_spawnp(&pid_, argv[0], nullptr, nullptr, argv.data(), environ) != 0) pid_ = -1;
  }
  ~FakeCameraProcess() { kill(); }
  bool started() const { return pid_ > 0; }
  // Stops the simulator (SIGSTOP) for `duration`, then lets it go on: it
  // hears nothing meanwhile, as a camera on a link that drops every packet.
  void pause(std::chrono::milliseconds duration) {
    ::kill(pid_, SIGSTOP);
    std::this_thread::sleep_for(duration);
    ::kill(pid_, SIGCONT);
  }
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
  // A 64 x 48 source at kAddress, open, that has delivered one frame.
  static std::unique_ptr<vision::GigeSource> small_source_with_a_frame(int retries) {
    vision::CaptureOptions options;
    options.width = 64;
    options.height = 48;
    options.retries = retries;
    auto source = std::make_unique<vision::GigeSource>(kAddress, options);
    source->open();
    source->trigger();
    EXPECT_FALSE(source->grab(kFrameWait).image.empty());
    return source;
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
  const vision::Frame frame = source.grab(kFrameWait);
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
  EXPECT_EQ(ramp_mismatches(source.grab(kFrameWait), 1.0 + std::log10(2.0)), 0);
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
  EXPECT_EQ(ramp_mismatches(source.grab(kFrameWait), 2.0), 0);
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
    const vision::Frame frame = source.grab(kFrameWait);
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
  EXPECT_FALSE(source.grab(kFrameWait).image.empty());
}

TEST_F(GigeFakeCamera, FreeRunStreamsWithoutLostFrames) {
  vision::CaptureOptions options;
  options.software_trigger = false;
  options.frame_rate_hz = 200;
  options.width = 320;
  options.height = 240;
  // A buffer for every frame grabbed: this thread may be descheduled for a
  // while without the stream running out of buffers (an underrun would lose
  // frames for want of room, not on the link, which is what is tested).
  options.n_buffers = 100;
  vision::GigeSource source(kAddress, options);
  source.open();
  for (int i = 0; i < 100; ++i)
    EXPECT_EQ(ramp_mismatches(source.grab(kFrameWait), 1.0), 0);
  EXPECT_EQ(source.counters().lost, 0u);
  EXPECT_EQ(source.counters().incomplete, 0u);
}

TEST_F(GigeFakeCamera, CameraKilledMidStreamIsACaptureErrorNotAFrame) {
  const auto source_ptr = small_source_with_a_frame(1);
  vision::GigeSource& source = *source_ptr;
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

TEST_F(GigeFakeCamera, ACameraThatMissedTheHeartbeatTakesControlAwayAndTheNextSourceGetsIt) {
  const auto source_ptr = small_source_with_a_frame(0);
  vision::GigeSource& source = *source_ptr;
  // The simulator keeps the GigE Vision default heartbeat timeout, 3 s: it
  // hears nothing for 4 s, so the first packet it handles afterwards finds
  // the controller's heartbeat expired and takes its control away
  // (arvgvfakecamera.c); Aravis's heartbeat (a read of the privilege
  // register once a second) then finds it gone.
  camera_.pause(4000ms);
  // Until that read, a grab sees no frame (CaptureTimeout). The deadline
  // only bounds a broken test: the read comes within seconds.
  bool lost = false;
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (!lost && std::chrono::steady_clock::now() < deadline) {
    try {
      source.trigger();
      source.grab(200ms);
      ADD_FAILURE() << "a frame after the camera's heartbeat expired";
      break;
    } catch (const vision::CaptureControlLost& e) {
      lost = true;
      EXPECT_NE(std::string(e.what()).find("gige:127.0.0.1: control of the camera lost"),
                std::string::npos)
          << e.what();
    } catch (const vision::CaptureTimeout&) {
    }
  }
  EXPECT_TRUE(lost);
  source.close();
  // The camera is free again: a new source takes control and gets a frame.
  small_source_with_a_frame(0);
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

// Resend off, and a network that loses exactly the packets a script names
// (GvspLossRelay): a data packet of frame 1, the leader of frame 3 and the
// trailer of frame 4, in the order the camera sends them. A damaged frame
// reaches the source incomplete once the frame retention (1 s) has passed
// with no later frame to close it. Every frame passed on must be one the
// relay passed whole, and whole pixel for pixel; the damaged ones must be
// counted, retried (retries = 1) and never returned.
TEST(GigeLossyCamera, IncompleteFramesAreCountedAndNeverPassedOn) {
  FakeCameraProcess camera;
  ASSERT_TRUE(camera.started()) << "arv-fake-gv-camera-0.8 not found (package aravis-tools)";
  ASSERT_TRUE(camera.wait_ready());
  constexpr const char* kLinkAddress = "127.0.0.3";  // the relay: loopback, no camera there
  const vision_test::GvspLossRelay link(
      kAddress, kLinkAddress, {{1, 1}, {3, 0}, {4, vision_test::GvspLossRelay::kTrailer}});
  vision::CaptureOptions options;
  options.width = 64;
  options.height = 48;
  options.packet_resend = false;
  options.retries = 1;
  vision::GigeSource source(kLinkAddress, options);
  source.open();
  ASSERT_TRUE(link.stream_redirected());
  std::vector<uint64_t> delivered;
  auto grab_whole = [&] {
    source.trigger();
    const vision::Frame frame = source.grab(kFrameWait);
    EXPECT_EQ(ramp_mismatches(frame, 1.0), 0) << "frame " << frame.frame_id;
    delivered.push_back(frame.frame_id);
  };
  grab_whole();  // frame 0
  grab_whole();  // frame 1 incomplete, retried: frame 2
  source.trigger();
  std::string refusal;
  try {
    source.grab(kFrameWait);  // frames 3 and 4 incomplete, no retry left
    ADD_FAILURE() << "a frame after two incomplete ones with one retry";
  } catch (const vision::CaptureTimeout& e) {
    ADD_FAILURE() << "timed out instead of seeing the incomplete frames: " << e.what();
  } catch (const vision::CaptureError& e) {
    refusal = e.what();
  }
  grab_whole();  // the source recovers: frame 5

  const std::vector<vision_test::GvspLossRelay::FrameTally> sent = link.frames();
  ASSERT_EQ(sent.size(), 6u);
  const std::vector<int> dropped_per_frame = {0, 1, 0, 1, 1, 0};
  for (size_t k = 0; k < sent.size(); ++k) {
    EXPECT_EQ(sent[k].dropped, dropped_per_frame[k]) << "frame " << k;
    EXPECT_GE(sent[k].forwarded, 2) << "frame " << k;  // at least a leader or trailer and data
  }
  EXPECT_EQ(link.unknown_packets(), 0);
  EXPECT_NE(refusal.find("frame " + std::to_string(sent[4].block_id) + " incomplete"),
            std::string::npos)
      << refusal;
  EXPECT_EQ(delivered,
            (std::vector<uint64_t>{sent[0].block_id, sent[2].block_id, sent[5].block_id}));
  const vision::CaptureCounters c = source.counters();
  EXPECT_EQ(c.delivered, 3u);
  EXPECT_EQ(c.incomplete, 3u);
  EXPECT_EQ(c.retries, 2u);  // frame 1's, and frame 3's
  EXPECT_EQ(c.timeouts, 0u);
  EXPECT_EQ(c.lost, 0u);
  EXPECT_EQ(c.discarded, 0u);
}

}  // namespace
