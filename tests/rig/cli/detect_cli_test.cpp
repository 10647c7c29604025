// `rig detect` as a user runs it: the real binary on image files rendered by
// sim::scene::SceneRenderer, its public JSON shape, and the files it must refuse.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>

#include "rig_command.hpp"
#include "sim/scene/renderer.hpp"
#include "vision/image_codecs.hpp"
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
    vision::imwrite(path("frame.png"), *image_);
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

// The image codecs (vision/image_codecs.hpp) are loaded to read an image,
// not when rig starts: `rig solve` reads no image and never loads them. The
// dynamic loader names each library it loads when LD_DEBUG=files.
TEST_F(RigDetect, LoadsTheImageCodecsOnlyToReadAnImage) {
  ASSERT_EQ(::setenv("LD_DEBUG", "files", 1), 0);
  const rig_test::RigRun solve = rig_test::run_rig("solve " + std::string(RIG_SOURCE_DIR) +
                                                   "/config/problems/paper_marker.json");
  const rig_test::RigRun detect = run(path("frame.png"));
  ASSERT_EQ(::unsetenv("LD_DEBUG"), 0);
  ASSERT_EQ(solve.exit_code, 0) << solve.err;
  ASSERT_EQ(detect.exit_code, 0) << detect.err;
  // The trace is there (the core library is linked), the codecs are not in it.
  EXPECT_NE(solve.err.find("file=libopencv_core"), std::string::npos) << solve.err.substr(0, 600);
  EXPECT_EQ(solve.err.find("libopencv_imgcodecs"), std::string::npos);
  EXPECT_NE(detect.err.find("file=libopencv_imgcodecs"), std::string::npos);
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
  vision::imencode(".png", *image_, png);
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
  vision::imwrite(path("wide.png"), wide);
  vision::imwrite(path("colour.png"), bgr);
  const rig_test::RigRun r = run("--json " + path("wide.png") + " " + path("colour.png"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const auto& j : json_lines(r.out))
    EXPECT_EQ(j["detections"].size(), 4u) << j["image"];
}

TEST_F(RigDetect, ImageOfAnotherSizeThanTheCameraIsRefused) {
  vision::imwrite(path("dot.png"), cv::Mat(1, 1, CV_8U, cv::Scalar(0)));
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

namespace {

// Every detector that decodes the target's family (rig4x4: all seven) reads
// the frame; the JSON says which found what, and each id is checked against
// the target layout. Every detector finds the four markers of the paper's
// sheet at 0.5 m (tests/vision/detectors_test.cpp: every marker with 8 px of
// white beyond it, at these distances and tilts).
TEST_F(RigDetect, SaysWhichDetectorFoundWhatAndChecksTheIdsAgainstTheTarget) {
  const rig_test::RigRun r = run("--json " + path("frame.png"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["detector"], "rig");
  ASSERT_EQ(j["detectors"].size(), 7u);
  for (const auto& d : j["detectors"]) {
    const std::string name = d["detector"];
    std::set<int> in_target;
    for (const auto& det : d["detections"]) {
      EXPECT_EQ(det["in_target"].get<bool>(), det["id"].get<int>() < 4) << name;
      if (det["in_target"].get<bool>()) in_target.insert(det["id"].get<int>());
    }
    EXPECT_EQ(in_target, (std::set<int>{0, 1, 2, 3})) << name;
    // libapriltag decodes rig's 16-bit codes without rig's border checks and
    // may take a quad of code cells for a marker (p = 0.2 % a quad,
    // vision/src/detectors_apriltag.cpp); the others find exactly the four.
    if (name.rfind("apriltag:", 0) != 0) {
      EXPECT_EQ(d["detections"].size(), 4u) << name;
    }
    EXPECT_FALSE(d["estimates"].empty()) << name;
  }
  const rig_test::RigRun one = run("--detector apriltag:d2 " + path("frame.png"));
  ASSERT_EQ(one.exit_code, 0) << one.err;
  EXPECT_NE(one.out.find("4 markers (detector apriltag:d2)"), std::string::npos) << one.out;
  EXPECT_EQ(one.out.find("detector rig)"), std::string::npos) << one.out;
}

// A detector that cannot decode the target's family is bad input (exit 2),
// naming the detector, the family and the detectors that can.
TEST_F(RigDetect, RefusesADetectorThatCannotReadTheTargetsFamily) {
  std::ifstream in(std::string(RIG_SOURCE_DIR) + "/config/targets/paper.toml");
  std::stringstream layout;
  layout << "family = \"aruco:DICT_6X6_250\"\n" << in.rdbuf();
  std::ofstream(path("aruco.toml")) << layout.str();
  const rig_test::RigRun r =
      run("--target " + path("aruco.toml") + " --detector rig " + path("frame.png"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--detector rig"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("aruco:DICT_6X6_250"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("aruco:subpix"), std::string::npos) << r.err;
}

}  // namespace
