// vision::RigGeometry: bench position -> T_cam_target, and the rig file.
#include "vision/rig_geometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace {

constexpr double kPi = 3.14159265358979323846;

vision::RigGeometry nominal() {
  return vision::RigGeometry::from_mount({0, 0, 0}, {0, 0, 0}, {600, 150, 0}, {0, 0, 0});
}

TEST(RigGeometry, NominalCameraLooksStraightAtTheTarget) {
  const vision::Pose T = nominal().T_cam_target(100, 150);
  EXPECT_TRUE(T.R.isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_TRUE(T.t.isApprox(Eigen::Vector3d(0, 0, 0.5), 1e-12)) << T.t.transpose();
}

TEST(RigGeometry, CarriageLeftOfTheTargetSeesItOnTheRight) {
  // The target is 50 mm further along bench +y, which is the camera's -x.
  const vision::Pose T = nominal().T_cam_target(100, 100);
  EXPECT_TRUE(T.t.isApprox(Eigen::Vector3d(-0.05, 0, 0.5), 1e-12)) << T.t.transpose();
}

TEST(RigGeometry, MisalignmentTurnsTheViewByItsAngle) {
  const auto g = vision::RigGeometry::from_mount({0, 0, 0}, {0, 0, 0.5}, {600, 150, 0}, {0, 0, 0});
  const vision::Pose T = g.T_cam_target(100, 150);
  EXPECT_NEAR(vision::rotation_angle_between(T.R, Eigen::Matrix3d::Identity()), 0.5 * kPi / 180,
              1e-12);
  EXPECT_NEAR(T.distance_m(), 0.5,
              1e-12);  // a rotation about the optical centre keeps the distance
}

TEST(RigGeometry, ShippedSimRigSpansThePapersTenToHundredCentimetresOverTheXTravel) {
  const auto g = vision::RigGeometry::load(std::string(RIG_SOURCE_DIR) + "/config/rigs/sim.toml");
  EXPECT_NEAR(g.distance_m(0, 150), 1.00, 1e-9);
  EXPECT_NEAR(g.distance_m(900, 150), 0.10, 1e-9);
  // The target faces the camera within the configured few degrees.
  EXPECT_LT(vision::rotation_angle_between(g.T_cam_target(450, 150).R, Eigen::Matrix3d::Identity()),
            3.0 * kPi / 180);
}

class RigFile : public ::testing::Test {
 protected:
  std::string write(const std::string& text) {
    path_ = std::filesystem::temp_directory_path() / "rig_geometry_test.toml";
    std::ofstream(path_) << text;
    return path_.string();
  }
  void TearDown() override { std::filesystem::remove(path_); }
  std::filesystem::path path_;
};

TEST_F(RigFile, MissingKeyIsAnErrorNamingFileAndKey) {
  const std::string path = write("[camera_mount]\noffset_mm = [0, 0, 0]\n");
  try {
    vision::RigGeometry::load(path);
    FAIL();
  } catch (const vision::RigConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("camera_mount.misalignment_deg"), std::string::npos)
        << e.what();
  }
}

TEST_F(RigFile, NonNumberElementIsAnErrorNamingIt) {
  const std::string path = write(
      "[camera_mount]\noffset_mm = [0, 0, 0]\nmisalignment_deg = [0, 0, 0]\n"
      "[target]\norigin_mm = [600, \"far\", 0]\ntilt_deg = [0, 0, 0]\n");
  try {
    vision::RigGeometry::load(path);
    FAIL();
  } catch (const vision::RigConfigError& e) {
    EXPECT_EQ(std::string(e.what()), path +
                                         ": target.origin_mm = [600, \"far\", 0]: expected "
                                         "[x, y, z], three finite numbers");
  }
}

TEST_F(RigFile, MisspeltKeyIsAnErrorNamingIt) {
  const std::string path = write(
      "[camera_mount]\noffset_mm = [0, 0, 0]\nmisalignment_deg = [0, 0, 0]\n"
      "[target]\norigin_mm = [600, 150, 0]\ntilt_deg = [0, 0, 0]\ntilt = [1, 0, 0]\n");
  try {
    vision::RigGeometry::load(path);
    FAIL();
  } catch (const vision::RigConfigError& e) {
    EXPECT_EQ(std::string(e.what()), path +
                                         ": target.tilt = [1, 0, 0]: unknown key (misspelt?); "
                                         "expected one of origin_mm, tilt_deg");
  }
}

TEST_F(RigFile, MissingFileIsAnErrorNamingIt) {
  EXPECT_THROW(vision::RigGeometry::load("/nonexistent/rig.toml"), vision::RigConfigError);
}

}  // namespace
