// V4l2Source. This machine (and CI) has no /dev/video* and its kernel cannot
// load vivid or v4l2loopback, so real capture is skipped, not faked; what is
// tested is that every device that cannot capture gives a clean CaptureError
// naming it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "vision/v4l2_source.hpp"

namespace {

using namespace std::chrono_literals;

std::string open_error(const std::string& path) {
  vision::V4l2Source source(path);
  try {
    source.open();
  } catch (const vision::CaptureError& e) {
    return e.what();
  }
  return "";
}

TEST(V4l2Source, MissingDeviceIsACaptureErrorNamingIt) {
  const std::string message = open_error("/dev/video97");
  EXPECT_NE(message.find("v4l2:/dev/video97"), std::string::npos) << message;
  EXPECT_NE(message.find("No such file"), std::string::npos) << message;
}

TEST(V4l2Source, CharacterDeviceThatIsNotV4l2IsRejected) {
  const std::string message = open_error("/dev/null");
  EXPECT_NE(message.find("not a V4L2 device"), std::string::npos) << message;
}

TEST(V4l2Source, RegularFileIsRejected) {
  const auto path = std::filesystem::temp_directory_path() / "rig_v4l2_not_a_device";
  std::ofstream(path) << "frames";
  const std::string message = open_error(path.string());
  std::filesystem::remove(path);
  EXPECT_NE(message.find("not a V4L2 device"), std::string::npos) << message;
}

TEST(V4l2Source, GrabBeforeOpenIsACaptureError) {
  vision::V4l2Source source("/dev/video0");
  EXPECT_THROW(source.grab(10ms), vision::CaptureError);
}

TEST(V4l2Source, CapturesFromARealDevice) {
  if (!std::filesystem::exists("/dev/video0"))
    GTEST_SKIP() << "no /dev/video0 here (and no vivid or v4l2loopback module): real V4L2 "
                    "capture is not tested on this machine";
  vision::V4l2Source source("/dev/video0");
  source.open();
  source.trigger();
  const vision::Frame frame = source.grab(2000ms);
  EXPECT_FALSE(frame.image.empty());
  EXPECT_GT(frame.camera_timestamp_ns, 0u);
}

}  // namespace
