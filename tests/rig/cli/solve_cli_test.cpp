// `rig solve` as a user runs it: the real binary, real files, exit codes.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "rig_command.hpp"
#include "vision/camera.hpp"

namespace {

namespace fs = std::filesystem;

using rig_test::RigRun;
using rig_test::run_rig;

const std::string kSample = std::string(RIG_SOURCE_DIR) + "/config/problems/paper_marker.json";

nlohmann::json sample() {
  std::ifstream in(kSample);
  return nlohmann::json::parse(in);
}

TEST(RigSolve, SampleProblemPrintsEverySolverAsJson) {
  const RigRun r = run_rig("solve --json " + kSample);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["estimates"].size(), 10u);
  for (const auto& e : j["estimates"]) {
    ASSERT_FALSE(e.contains("skipped")) << e.dump();
    EXPECT_EQ(e["R"].size(), 3u);
    EXPECT_EQ(e["t"].size(), 3u);
    for (const char* key :
         {"distance_m", "reprojection_error_px", "converged", "iterations", "time_us"})
      EXPECT_TRUE(e.contains(key)) << key;
  }
  // The sample is 0.450 m away with 0.2 px noise: lm's distance is within
  // 1 % (five times the 0.2 % that 0.2 px gives at this range).
  for (const auto& e : j["estimates"]) {
    const double distance = e["distance_m"];
    if (e["solver"] == "lm") {
      EXPECT_NEAR(distance, 0.450, 0.0045);
    }
    if (e["solver"] == "ippe") {
      EXPECT_TRUE(e.contains("ambiguity_ratio"));
    }
  }
}

TEST(RigSolve, TableIsTheDefaultAndReadsStandardInput) {
  std::ifstream in(kSample);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  const RigRun r = run_rig("solve -", text);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("hybrid_ekf"), std::string::npos);
  EXPECT_NE(r.out.find("opencv_sqpnp"), std::string::npos);
}

TEST(RigSolve, SquareOnlySolversSaySkippedOnSixteenPoints) {
  auto j = sample();
  // Four copies of the marker, 7 cm apart, all seen frontally at 0.5 m.
  nlohmann::json obj = nlohmann::json::array(), img = nlohmann::json::array();
  for (double cx : {0.0, 0.07})
    for (double cy : {0.0, 0.07})
      for (auto [dx, dy] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
        const double x = cx + dx * 0.025, y = cy + dy * 0.025;
        obj.push_back({x, y, 0.0});
        img.push_back({706.1 * x / 0.5 + 388.0, 731.1 * y / 0.5 + 269.6});
      }
  j["camera"]["dist"] = {0, 0, 0, 0, 0};
  j["object_points"] = obj;
  j["image_points"] = img;
  const RigRun r = run_rig("solve --json -", j.dump());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto out = nlohmann::json::parse(r.out);
  int skipped = 0;
  for (const auto& e : out["estimates"])
    if (e.contains("skipped")) {
      ++skipped;
      EXPECT_TRUE(e["solver"] == "analytic" || e["solver"] == "opencv_ippe_square") << e.dump();
    } else {
      const double distance = e["distance_m"];
      EXPECT_NEAR(distance, 0.5, 1e-6) << e.dump();  // exact data
    }
  EXPECT_EQ(skipped, 2);
}

// A camera with a thin prism given as OpenCV's 12 coefficients: the points
// are undistorted through it before solving, so every solver finds the
// exact distance (1e-6 m: exact data, the solvers' own convergence). A
// rational k4 is refused naming the coefficient.
TEST(RigSolve, ThinPrismCoefficientsAreAppliedBeforeSolving) {
  vision::Distortion d;
  d.s1 = 1e-3;
  d.s3 = -8e-4;
  const vision::Camera camera({706.1, 731.1, 388.0, 269.6}, d, 736, 571);
  nlohmann::json obj = nlohmann::json::array(), img = nlohmann::json::array();
  for (double cx : {-0.1, 0.1})
    for (double cy : {-0.1, 0.1})
      for (auto [dx, dy] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
        const double x = cx + dx * 0.025, y = cy + dy * 0.025;
        obj.push_back({x, y, 0.0});
        const Eigen::Vector2d px = camera.project({x, y, 0.5});
        img.push_back({px.x(), px.y()});
      }
  auto j = sample();
  j["camera"]["dist"] = {0, 0, 0, 0, 0, 0, 0, 0, d.s1, 0, d.s3, 0};
  j["object_points"] = obj;
  j["image_points"] = img;
  const RigRun r = run_rig("solve --json -", j.dump());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int solved = 0;
  const nlohmann::json out = nlohmann::json::parse(r.out);
  for (const auto& e : out["estimates"])
    if (!e.contains("skipped")) {
      EXPECT_NEAR(e["distance_m"].get<double>(), 0.5, 1e-6) << e.dump();
      ++solved;
    }
  EXPECT_GE(solved, 8);
  j["camera"]["dist"][5] = 0.01;  // k4: OpenCV's rational model
  const RigRun rational = run_rig("solve -", j.dump());
  EXPECT_EQ(rational.exit_code, 2) << rational.err;
  EXPECT_NE(rational.err.find("'camera.dist[5]' is a rational term"), std::string::npos)
      << rational.err;
}

void expect_bad_input(const std::string& stdin_text, const std::string& words) {
  const RigRun r = run_rig("solve -", stdin_text);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(words), std::string::npos) << r.err;
}

TEST(RigSolve, MalformedJsonExitsTwo) {
  expect_bad_input("{\"camera\": ", "not valid JSON");
}

TEST(RigSolve, FewerThanFourPointsExitsTwo) {
  auto j = sample();
  j["object_points"].erase(3);
  j["image_points"].erase(3);
  expect_bad_input(j.dump(), "expected at least 4");
}

TEST(RigSolve, DifferentCountsExitTwo) {
  auto j = sample();
  j["image_points"].erase(3);
  expect_bad_input(j.dump(), "4 object points but 3 image points");
}

TEST(RigSolve, NonNumbersAndNonFiniteValuesExitTwo) {
  auto j = sample();
  j["image_points"][1][0] = "NaN";
  expect_bad_input(j.dump(), "image_points[1][0] must be a number");
  expect_bad_input("{\"camera\": {}, \"object_points\": [], \"image_points\": [[NaN, 1]]}",
                   "not valid JSON");
  j = sample();
  j["camera"]["fx"] = -1;
  expect_bad_input(j.dump(), "fx and fy must be finite and > 0");
}

TEST(RigSolve, MissingKeysAreNamed) {
  auto j = sample();
  j.erase("camera");
  expect_bad_input(j.dump(), "key 'camera' (or 'camera_file') is missing");
  j = sample();
  j["camera"].erase("width");
  expect_bad_input(j.dump(), "key 'camera.width' is missing");
}

TEST(RigSolve, CameraFileIsResolvedNextToTheProblem) {
  const fs::path dir = fs::temp_directory_path() / ("rig_solve_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "cam.yaml")
      << "%YAML:1.0\nimage_width: 736\nimage_height: 571\ncamera_matrix: !!opencv-matrix\n"
         "  rows: 3\n  cols: 3\n  dt: d\n  data: [706.1, 0, 388.0, 0, 731.1, 269.6, 0, 0, 1]\n"
         "distortion_coefficients: !!opencv-matrix\n  rows: 1\n  cols: 5\n  dt: d\n"
         "  data: [-0.2279, 0.1479, -0.0007985, 0.0006245, 0]\n";
  auto j = sample();
  j.erase("camera");
  j["camera_file"] = "cam.yaml";
  std::ofstream(dir / "problem.json") << j.dump();
  const RigRun ok = run_rig("solve " + (dir / "problem.json").string());
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  j["camera_file"] = "missing.yaml";
  std::ofstream(dir / "problem.json") << j.dump();
  const RigRun bad = run_rig("solve " + (dir / "problem.json").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("missing.yaml': cannot be opened"), std::string::npos) << bad.err;
  fs::remove_all(dir);
}

TEST(RigSolve, MissingProblemFileIsNamed) {
  const RigRun r = run_rig("solve /nonexistent/problem.json");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("'/nonexistent/problem.json': cannot be opened"), std::string::npos)
      << r.err;
}

}  // namespace
