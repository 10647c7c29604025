// `rig report` on a run that saved its frames: the page holds pictures of
// them with the detections drawn exactly where the database says (checked
// pixel by pixel in the embedded PNGs).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "db/store/store.hpp"
#include "file_bytes.hpp"
#include "rig_command.hpp"
#include "sim_rig_fixture.hpp"
#include "vision/image_codecs.hpp"

namespace {

using rig_test::SimRig;
using rig_test::SweepFileOptions;

std::string unbase64(const std::string& text) {
  std::string out;
  int bits = 0;
  std::uint32_t value = 0;
  for (char c : text) {
    int v = -1;
    if (c >= 'A' && c <= 'Z') v = c - 'A';
    if (c >= 'a' && c <= 'z') v = c - 'a' + 26;
    if (c >= '0' && c <= '9') v = c - '0' + 52;
    if (c == '+') v = 62;
    if (c == '/') v = 63;
    if (v < 0) continue;  // padding
    value = (value << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out += static_cast<char>((value >> bits) & 0xFF);
    }
  }
  return out;
}

// The PNG of the page's picture `id`, decoded (BGR).
cv::Mat picture(const std::string& html, const std::string& id) {
  const auto at = html.find("<figure class=\"frame\" id=\"" + id + "\"");
  if (at == std::string::npos) return {};
  const std::string prefix = "data:image/png;base64,";
  const auto begin = html.find(prefix, at) + prefix.size();
  const std::string png = unbase64(html.substr(begin, html.find('"', begin) - begin));
  return vision::imdecode(std::vector<unsigned char>(png.begin(), png.end()), cv::IMREAD_COLOR);
}

// What `rig report` draws with (rig/cli/src/cmd_report.cpp): Okabe-Ito orange.
const cv::Vec3b kOrange(0, 159, 230);

TEST(ReportFrames, ShowSavedFramesWithTheDetectedCornersDrawnWhereTheDetectionsSay) {
  SimRig rig;
  SweepFileOptions o;
  o.extra_capture = "save_frames = \"" + rig.file("frames") + "\"\n";
  const std::string sweep = rig.write_sweep(o);
  const auto run = rig_test::run_rig("sweep " + sweep + " --no-progress");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto r = rig_test::run_rig("report " + rig.database() + " --out " + rig.file("report"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const std::string html = rig_test::file_bytes(rig.file("report/report.html"));
  const nlohmann::json json =
      nlohmann::json::parse(rig_test::file_bytes(rig.file("report/report.json")));
  // The fixture's six positions (x 300..800 mm in 100 mm steps) are about
  // 0.1 m apart in distance, wider than a class (0.09 m): each class shows
  // its first positions, so at least five pictures.
  ASSERT_GE(json["pictures"].size(), 5u);

  db::store::StoreOptions options;
  options.read_only = true;
  const db::store::Store store(rig.database(), options);
  std::size_t corners_checked = 0;
  for (const auto& p : json["pictures"]) {
    const std::int64_t plan = p["plan_index"];
    const int frame = p["frame_index"];
    const double scale = p["scale"];
    const cv::Mat image =
        picture(html, "frame-p" + std::to_string(plan) + "-f" + std::to_string(frame));
    ASSERT_FALSE(image.empty()) << plan << "/" << frame;
    EXPECT_EQ(image.cols, p["width_px"].get<int>());
    EXPECT_LE(image.cols, 360);
    const db::store::FrameRecord f = store.position(1, plan).frames.at(frame);
    ASSERT_FALSE(f.detections.empty());
    // Every corner of every detection is an orange dot at corner x scale
    // (rounded to the pixel: the picture's pixel grid), and nothing else
    // orange is where no detection is: the picture's top-left 5 x 5 pixels
    // are background (the fixture's markers are never at the image's corner).
    for (const db::store::DetectionRecord& d : f.detections) {
      for (int c = 0; c < 4; ++c) {
        const int x = static_cast<int>(std::lround(d.corners_px[2 * c] * scale));
        const int y = static_cast<int>(std::lround(d.corners_px[2 * c + 1] * scale));
        ASSERT_TRUE(x >= 0 && y >= 0 && x < image.cols && y < image.rows);
        EXPECT_EQ(image.at<cv::Vec3b>(y, x), kOrange)
            << "marker " << d.marker_id << " corner " << c << " of " << plan << "/" << frame;
        ++corners_checked;
      }
    }
    for (int y = 0; y < 5; ++y)
      for (int x = 0; x < 5; ++x)
        EXPECT_NE(image.at<cv::Vec3b>(y, x), kOrange);
  }
  EXPECT_GE(corners_checked, 5u * 4u);
}

// Without saved frames the page says how to get pictures, and rig report
// stays quiet about it (not an error of the run).
TEST(ReportFrames, SayHowToGetThemWhenTheRunSavedNone) {
  SimRig rig;
  SweepFileOptions o;
  o.plan = "kind = \"grid\"\nx_mm = [300.0, 400.0, 100.0]\ny_mm = [150.0, 150.0, 10.0]\n";
  const auto run = rig_test::run_rig("sweep " + rig.write_sweep(o) + " --no-progress");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto r = rig_test::run_rig("report " + rig.database() + " --out " + rig.file("report"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const std::string html = rig_test::file_bytes(rig.file("report/report.html"));
  EXPECT_EQ(html.find("<figure class=\"frame\""), std::string::npos);
  EXPECT_NE(html.find("[capture] save_frames"), std::string::npos);
}

}  // namespace
