// `rig calibrate` as a user runs it: the files it writes are read back by the
// loaders rig uses, and bad input exits 2 naming the input.
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "rig/calibrate/calibration.hpp"
#include "rig_command.hpp"
#include "store_fixture.hpp"
#include "synthetic_calibration.hpp"

namespace {

std::string write_run(const db_test::ScratchDir& dir, std::vector<std::pair<double, double>> plan) {
  rig_test::SyntheticCalibrationSpec spec;
  spec.true_camera = rig_test::calibration_true_camera();
  spec.true_geometry = rig_test::calibration_true_geometry();
  spec.nominal_rig_toml = rig_test::calibration_nominal_rig_toml();
  spec.plan = std::move(plan);
  spec.seed = 11;
  spec.target_layout_path = rig_test::calibration_target_path(RIG_SOURCE_DIR);
  const std::string db = dir.file("calibration.db");
  rig_test::write_calibration_run(db, spec);
  return db;
}

TEST(CalibrateCli, WritesFilesThatRigReads) {
  const db_test::ScratchDir dir;
  const std::string db =
      write_run(dir, rig_test::read_csv_plan(rig_test::calibration_plan_path(RIG_SOURCE_DIR)));
  const std::string out = dir.file("out");
  const rig_test::RigRun r = rig_test::run_rig("calibrate " + db + ":1 --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const vision::Camera truth = rig_test::calibration_true_camera();
  // Both camera files hold the same calibration; 0.02 % of fx as in the
  // library's accuracy test.
  for (const char* file : {"/camera.yaml", "/camera_info.yaml"}) {
    const vision::Camera cam = vision::Camera::load(out + file);
    EXPECT_NEAR(cam.intrinsics().fx, truth.intrinsics().fx, 2e-4 * truth.intrinsics().fx) << file;
  }
  // The rig file gives the true camera-to-target distance at bench zero
  // within 20 um, and the nominal camera offset (the convention).
  const vision::RigGeometry g = vision::RigGeometry::load(out + "/rig.toml");
  EXPECT_NEAR(g.distance_m(0, 0), rig_test::calibration_true_geometry().distance_m(0, 0), 20e-6);
  EXPECT_EQ(g.T_carriage_cam.t, Eigen::Vector3d::Zero());
  std::ifstream in(out + "/calibration.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  const auto n = static_cast<std::size_t>(rig::calibrate::kParameterCount);
  EXPECT_EQ(j["parameters"].size(), n);
  EXPECT_EQ(j["correlation"]["matrix"].size(), n);
  EXPECT_GT(j["held_out"]["held_out_positions"].get<int>(), 100);
  // Held out, the prediction is at the noise floor: 0.1 px per coordinate is
  // 0.141 px of |r|; +10 % for the parameter error.
  EXPECT_LT(j["held_out"]["held_out_rms_px"].get<double>(), 0.156);
}

// --distortion thin_prism: the fitted s1..s4 reach both camera files (12
// coefficients in OpenCV's order) exactly as calibration.json states them
// (written with 12 significant digits: a relative 1e-11).
TEST(CalibrateCli, ThinPrismReachesBothCameraFiles) {
  const db_test::ScratchDir dir;
  const std::string db =
      write_run(dir, rig_test::read_csv_plan(rig_test::calibration_plan_path(RIG_SOURCE_DIR)));
  const std::string out = dir.file("out");
  const rig_test::RigRun r =
      rig_test::run_rig("calibrate " + db + ":1 --distortion thin_prism --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(out + "/calibration.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  std::array<double, 4> s{};
  for (const nlohmann::json& p : j["parameters"])
    for (int k = 0; k < 4; ++k)
      if (p["name"] == "s" + std::to_string(k + 1)) {
        EXPECT_FALSE(p["fixed"].get<bool>());
        s[static_cast<std::size_t>(k)] = p["value"].get<double>();
      }
  ASSERT_NE(s[0], 0.0);  // a fit with noise never lands on exactly 0
  for (const char* file : {"/camera.yaml", "/camera_info.yaml"}) {
    const vision::Camera cam = vision::Camera::load(out + file);
    EXPECT_EQ(cam.distortion_cv().cols, 12) << file;
    const vision::Distortion& d = cam.distortion();
    const std::array<double, 4> got{d.s1, d.s2, d.s3, d.s4};
    for (std::size_t k = 0; k < 4; ++k)
      EXPECT_NEAR(got[k], s[k], 1e-11 * std::abs(s[k]) + 1e-300) << file << " s" << k + 1;
  }
  const rig_test::RigRun bad =
      rig_test::run_rig("calibrate " + db + " --distortion 8 --out " + out);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--distortion"), std::string::npos) << bad.err;
}

TEST(CalibrateCli, BadInputExitsTwoNamingIt) {
  const db_test::ScratchDir dir;
  rig_test::RigRun r =
      rig_test::run_rig("calibrate " + dir.file("missing.db") + " --out " + dir.file("out"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("missing.db: no such run database"), std::string::npos) << r.err;

  std::vector<std::pair<double, double>> one_distance;
  for (double y = 0; y <= 300; y += 50)
    one_distance.emplace_back(300.0, y);
  const std::string db = write_run(dir, one_distance);
  r = rig_test::run_rig("calibrate " + db + ":7 --out " + dir.file("out"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("there is no run 7"), std::string::npos) << r.err;
  r = rig_test::run_rig("calibrate " + db + " --out " + dir.file("out"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("fx/fy and target distance are not separable"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("out")));
}

}  // namespace
