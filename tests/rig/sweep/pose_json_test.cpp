// rig::sweep::pose_to_json: the one JSON form of a pose, stored with a run
// (runs.config_json) and printed by rig solve and rig detect.
#include "rig/sweep/pose_json.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

namespace {

TEST(PoseJson, WritesRotationRowByRowAndTheTranslationUnderTheFormatsKey) {
  vision::Pose T;
  T.R = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  T.t = {0.125, -0.25, 1.5};
  const nlohmann::json j = rig::sweep::pose_to_json(T, "t_m");
  ASSERT_EQ(j.size(), 2u) << j.dump();
  ASSERT_EQ(j["R"].size(), 3u);
  for (int r = 0; r < 3; ++r) {
    ASSERT_EQ(j["R"][r].size(), 3u);
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(j["R"][r][c].get<double>(), T.R(r, c)) << r << " " << c;  // doubles as they are
  }
  EXPECT_EQ(j["t_m"], nlohmann::json({0.125, -0.25, 1.5}));
  EXPECT_EQ(rig::sweep::pose_to_json(T, "t")["t"], j["t_m"]);
}

TEST(PoseJson, NonFiniteValuesAreNull) {
  vision::Pose T;
  T.R(1, 2) = std::numeric_limits<double>::quiet_NaN();
  T.t = {std::numeric_limits<double>::infinity(), 0, 1};
  const nlohmann::json j = rig::sweep::pose_to_json(T, "t");
  EXPECT_TRUE(j["R"][1][2].is_null()) << j.dump();
  EXPECT_EQ(j["R"][1][1], 1.0);
  EXPECT_TRUE(j["t"][0].is_null()) << j.dump();
  EXPECT_EQ(j["t"][2], 1.0);
  EXPECT_TRUE(rig::sweep::finite_or_null(-std::numeric_limits<double>::infinity()).is_null());
  EXPECT_EQ(rig::sweep::finite_or_null(-0.5), -0.5);
}

}  // namespace
