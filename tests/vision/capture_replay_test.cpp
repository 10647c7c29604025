// ReplaySource and the source factory, on images written by the test.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "vision/frame_source.hpp"
#include "vision/image_codecs.hpp"
#include "vision/replay_source.hpp"

namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

class ReplayFolder : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rig_replay_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  // An image whose every pixel is `value`, so the order can be read back.
  void write_image(const std::string& name, uint8_t value) {
    vision::imwrite((dir_ / name).string(), cv::Mat(12, 16, CV_8UC1, cv::Scalar(value)));
  }
  fs::path dir_;
};

TEST_F(ReplayFolder, DeliversImagesInNameOrderThenEndOfFrames) {
  write_image("frame_002.png", 2);
  write_image("frame_000.png", 0);
  write_image("frame_001.pgm", 1);
  std::ofstream(dir_ / "notes.txt") << "not an image";
  auto source = vision::make_frame_source("replay:" + dir_.string());
  source->open();
  for (int i = 0; i < 3; ++i) {
    source->trigger();
    const vision::Frame frame = source->grab(0ms);
    EXPECT_EQ(frame.frame_id, static_cast<uint64_t>(i));
    EXPECT_EQ(frame.image.type(), CV_8UC1);
    EXPECT_EQ(frame.image.at<uint8_t>(0, 0), i);
  }
  EXPECT_THROW(source->grab(0ms), vision::EndOfFrames);
  EXPECT_EQ(source->counters().delivered, 3u);
}

TEST_F(ReplayFolder, CorruptImageIsAnErrorNamingItAndTheOthersAreStillDelivered) {
  write_image("a.png", 10);
  std::ofstream(dir_ / "b.png") << "\x89PNG truncated";
  write_image("c.png", 30);
  vision::ReplaySource source(dir_.string());
  source.open();
  EXPECT_EQ(source.grab(0ms).image.at<uint8_t>(0, 0), 10);
  try {
    source.grab(0ms);
    FAIL() << "a corrupt image was delivered";
  } catch (const vision::CaptureError& e) {
    EXPECT_NE(std::string(e.what()).find("b.png"), std::string::npos) << e.what();
  }
  EXPECT_EQ(source.grab(0ms).image.at<uint8_t>(0, 0), 30);
  EXPECT_EQ(source.counters().incomplete, 1u);
  EXPECT_EQ(source.counters().delivered, 2u);
}

TEST_F(ReplayFolder, ListIsReplayedInTheGivenOrder) {
  write_image("x.png", 7);
  write_image("y.png", 9);
  vision::ReplaySource source(
      std::vector<std::string>{(dir_ / "y.png").string(), (dir_ / "x.png").string()});
  source.open();
  EXPECT_EQ(source.grab(0ms).image.at<uint8_t>(0, 0), 9);
  EXPECT_EQ(source.grab(0ms).image.at<uint8_t>(0, 0), 7);
}

TEST_F(ReplayFolder, EmptyOrMissingFolderIsACaptureError) {
  EXPECT_THROW(vision::ReplaySource(dir_.string()).open(), vision::CaptureError);
  EXPECT_THROW(vision::ReplaySource((dir_ / "absent").string()).open(), vision::CaptureError);
}

TEST(FrameSourceSpec, UnknownSchemeOrEmptyDeviceIsRejected) {
  EXPECT_THROW(vision::make_frame_source("usb:cam0"), std::invalid_argument);
  EXPECT_THROW(vision::make_frame_source("gige:"), std::invalid_argument);
  EXPECT_THROW(vision::make_frame_source("/dev/video0"), std::invalid_argument);
  EXPECT_EQ(vision::make_frame_source("gige:127.0.0.1")->name(), "gige:127.0.0.1");
  EXPECT_EQ(vision::make_frame_source("v4l2:/dev/video3")->name(), "v4l2:/dev/video3");
}

}  // namespace
