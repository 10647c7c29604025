// `rig detect` as a user runs it: the real binary on image files rendered by
// sim::scene::SceneRenderer, its public JSON shape, and the files it must refuse.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "rig_command.hpp"
#include "sim/scene/renderer.hpp"
#include "vision/solvers.hpp"

namespace {

namespace fs = std::filesystem;

// `rig detect ARGS`, stdout and stderr apart.
rig_test::RigRun run(const std::string& args) {
  return rig_test::run_rig("detect " + args);
}

std::vector<nlohmann::json> json_lines(const std::string& text) {
  std::vector<nlohmann::json> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    out.push_back(nlohmann::json::parse(line));
  return out;
}

// The paper's sheet at 0.5 m, tilted 17 degrees: all four markers in view.
class RigDetect : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() / ("rig_detect_" + std::to_string(::getpid())));
    fs::create_directories(*dir_);
    const sim::scene::SceneRenderer renderer(vision::Camera::paper_default(),
                                             vision::Target::paper_default(), vision::Codebook());
    pose_ = new vision::Pose;
    pose_->R = Eigen::Matrix3d(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 0.5, 0).normalized()));
    pose_->t = Eigen::Vector3d(0.01, 0.0, 0.5);
    image_ = new cv::Mat(renderer.render(*pose_, 3).image);
    cv::imwrite(path("frame.png"), *image_);
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete pose_;
    delete image_;
  }
  static std::string path(const std::string& name) { return (*dir_ / name).string(); }

  static fs::path* dir_;
  static vision::Pose* pose_;
  static cv::Mat* image_;
};
fs::path* RigDetect::dir_ = nullptr;
vision::Pose* RigDetect::pose_ = nullptr;
cv::Mat* RigDetect::image_ = nullptr;

TEST_F(RigDetect, PrintsDetectionsAndEveryEstimateInThePublicJsonShape) {
  const rig_test::RigRun r = run("--json " + path("frame.png"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto lines = json_lines(r.out);
  ASSERT_EQ(lines.size(), 1u);
  const auto& j = lines[0];
  EXPECT_EQ(j["image"], path("frame.png"));
  ASSERT_EQ(j["detections"].size(), 4u);
  for (int i = 0; i < 4; ++i) {
    const auto& d = j["detections"][i];
    EXPECT_EQ(d["id"], i);
    EXPECT_TRUE(d["rotation"].is_number_integer());
    ASSERT_EQ(d["corners"].size(), 4u);
    for (const auto& c : d["corners"])
      EXPECT_EQ(c.size(), 2u);
    for (const char* key : {"contrast", "bits_corrected", "edge_fit_residual_px"})
      EXPECT_TRUE(d["quality"].contains(key)) << key;
  }
  // Every solver once per scope: the pose marker (its id, 0) and the target.
  const auto& names = vision::solver_names();
  ASSERT_EQ(j["estimates"].size(), 2 * names.size());
  for (size_t k = 0; k < j["estimates"].size(); ++k) {
    const auto& e = j["estimates"][k];
    EXPECT_EQ(e["solver"], names[k % names.size()]);
    EXPECT_EQ(e["scope"], k < names.size() ? nlohmann::json(0) : nlohmann::json("target"));
    if (e.contains("skipped")) continue;  // e.g. a square-only solver on 16 points
    for (const char* key :
         {"R", "t", "distance_m", "reprojection_error_px", "converged", "ambiguity_ratio"})
      EXPECT_TRUE(e.contains(key)) << key << " in " << e.dump();
  }
}

// Corners within ~0.01 px give the distance within 0.01 % at 0.5 m; 0.05 %
// leaves room for the solver's own tolerance.
TEST_F(RigDetect, MaximumLikelihoodDistanceMatchesTheRenderedPose) {
  const rig_test::RigRun r = run("--json " + path("frame.png"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double truth = pose_->t.norm();
  int checked = 0;
  const auto lines = json_lines(r.out);
  for (const auto& e : lines[0]["estimates"])
    if (e["solver"] == "lm") {
      EXPECT_NEAR(e["distance_m"].get<double>(), truth, 5e-4 * truth) << e["scope"];
      ++checked;
    }
  EXPECT_EQ(checked, 2);
}

TEST_F(RigDetect, BadFilesAreNamedAndTheOtherImagesStillProcessed) {
  std::ofstream(path("empty.png"));
  std::ofstream(path("notes.png")) << "not an image\n";
  std::vector<uchar> png;
  cv::imencode(".png", *image_, png);
  std::ofstream(path("truncated.png"), std::ios::binary)
      .write(reinterpret_cast<const char*>(png.data()),
             static_cast<std::streamsize>(png.size() / 2));
  const std::vector<std::string> bad = {"missing.png", "empty.png", "notes.png", "truncated.png"};
  std::string args = "--json";
  for (const auto& b : bad)
    args += " " + path(b);
  args += " " + path("frame.png");
  const rig_test::RigRun r = run(args);
  EXPECT_EQ(r.exit_code, 2);
  const auto lines = json_lines(r.out);
  ASSERT_EQ(lines.size(), bad.size() + 1);
  for (size_t i = 0; i < bad.size(); ++i) {
    EXPECT_EQ(lines[i]["image"], path(bad[i]));
    EXPECT_TRUE(lines[i].contains("error"));
    EXPECT_TRUE(lines[i]["detections"].empty());
    EXPECT_NE(r.err.find("image '" + path(bad[i]) + "'"), std::string::npos) << r.err;
  }
  EXPECT_NE(r.err.find("cannot be opened"), std::string::npos);
  EXPECT_NE(r.err.find("is empty"), std::string::npos);
  EXPECT_NE(r.err.find("is not an image"), std::string::npos);
  EXPECT_NE(r.err.find("is truncated"), std::string::npos);
  EXPECT_EQ(lines.back()["detections"].size(), 4u);
}

TEST_F(RigDetect, SixteenBitAndColourImagesAreConverted) {
  cv::Mat wide, bgr;
  image_->convertTo(wide, CV_16U, 256.0);
  cv::cvtColor(*image_, bgr, cv::COLOR_GRAY2BGR);
  cv::imwrite(path("wide.png"), wide);
  cv::imwrite(path("colour.png"), bgr);
  const rig_test::RigRun r = run("--json " + path("wide.png") + " " + path("colour.png"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const auto& j : json_lines(r.out))
    EXPECT_EQ(j["detections"].size(), 4u) << j["image"];
}

TEST_F(RigDetect, ImageOfAnotherSizeThanTheCameraIsRefused) {
  cv::imwrite(path("dot.png"), cv::Mat(1, 1, CV_8U, cv::Scalar(0)));
  const rig_test::RigRun r = run(path("dot.png"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("the built-in paper camera (no --camera) is for 736x571 px but image '" +
                       path("dot.png") + "' is 1x1 px"),
            std::string::npos)
      << r.err;
}

TEST_F(RigDetect, TextOutputListsTheMarkersAndTheSolvers) {
  const rig_test::RigRun r = run(path("frame.png"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find(path("frame.png") + ": 4 markers"), std::string::npos) << r.out;
  for (const auto& name : vision::solver_names())
    EXPECT_NE(r.out.find(name), std::string::npos) << name;
}

}  // namespace
