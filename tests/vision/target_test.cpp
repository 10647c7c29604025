// vision::Target: the paper's sheet, corner order and the layout file.
#include "vision/target.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>
#include <string>

namespace vision {
namespace {

std::string write_temp(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("rig_target_test_" + name + ".toml");
  std::ofstream(path) << text;
  return path.string();
}

std::string error_of(const std::string& path) {
  try {
    Target::load(path);
  } catch (const TargetError& e) {
    return e.what();
  }
  return "(no error)";
}

const std::string kHeader = "paper = \"A4\"\norigin_mm = [105.0, 148.5]\npose_marker = 0\n";

TEST(Target, ShippedPaperLayoutEqualsTheBuiltInDefault) {
  const Target file = Target::load(RIG_SOURCE_DIR "/config/targets/paper.toml");
  const Target def = Target::paper_default();
  ASSERT_EQ(file.markers.size(), 4u);
  ASSERT_EQ(def.markers.size(), 4u);
  EXPECT_EQ(file.pose_marker_id, 0);
  EXPECT_EQ(file.quiet_cells, def.quiet_cells);
  EXPECT_DOUBLE_EQ(file.sheet_width_m, 0.210);
  EXPECT_DOUBLE_EQ(file.sheet_height_m, 0.297);
  EXPECT_TRUE(file.sheet_origin_m.isApprox(def.sheet_origin_m));
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(file.markers[i].id, static_cast<int>(i));
    EXPECT_EQ(file.markers[i].id, def.markers[i].id);
    EXPECT_DOUBLE_EQ(file.markers[i].side_m, 0.050);
    EXPECT_NEAR((file.markers[i].centre_m - def.markers[i].centre_m).norm(), 0, 1e-12);
  }
  EXPECT_NO_THROW(def.validate());
}

TEST(Target, PoseMarkerIsCentredAtTheOriginWithCornersABCDClockwise) {
  const Target t = Target::paper_default();
  const auto c = t.corners_m(t.pose_marker());
  EXPECT_TRUE(c[0].isApprox(Eigen::Vector3d(-0.025, -0.025, 0)));  // A top-left
  EXPECT_TRUE(c[1].isApprox(Eigen::Vector3d(0.025, -0.025, 0)));   // B top-right
  EXPECT_TRUE(c[2].isApprox(Eigen::Vector3d(0.025, 0.025, 0)));    // C bottom-right
  EXPECT_TRUE(c[3].isApprox(Eigen::Vector3d(-0.025, 0.025, 0)));   // D bottom-left
  // Clockwise as printed (y down): the z of (B - A) x (C - B) points into the sheet.
  EXPECT_GT((c[1] - c[0]).cross(c[2] - c[1]).z(), 0);
}

TEST(Target, UnknownMarkerIdThrowsTargetError) {
  EXPECT_THROW(Target::paper_default().marker(7), TargetError);
}

TEST(Target, MissingFileNamesTheFile) {
  const std::string message = error_of("/nonexistent/layout.toml");
  EXPECT_NE(message.find("/nonexistent/layout.toml"), std::string::npos) << message;
}

TEST(Target, WrongTypeNamesFileKeyValueAndExpectation) {
  const std::string path = write_temp(
      "wrong_type", kHeader + "[[markers]]\nid = 0\nside_mm = \"fifty\"\ncentre_mm = [0, 0]\n");
  const std::string message = error_of(path);
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("markers[0].side_mm"), std::string::npos) << message;
  EXPECT_NE(message.find("\"fifty\""), std::string::npos) << message;
  EXPECT_NE(message.find("expected"), std::string::npos) << message;
}

TEST(Target, MarkerOffTheSheetIsRejected) {
  const std::string path =
      write_temp("off_sheet", kHeader + "[[markers]]\nid = 0\nside_mm = 50\ncentre_mm = [90, 0]\n");
  const std::string message = error_of(path);
  EXPECT_NE(message.find("markers[0].centre_mm"), std::string::npos) << message;
  EXPECT_NE(message.find("[90, 0]"), std::string::npos) << message;
}

TEST(Target, OverlappingQuietZonesAreRejected) {
  // Two 50 mm markers with 1-cell quiet zones need 66.7 mm between centres.
  const std::string path =
      write_temp("overlap", kHeader +
                                "[[markers]]\nid = 0\nside_mm = 50\ncentre_mm = [0, 0]\n"
                                "[[markers]]\nid = 1\nside_mm = 50\ncentre_mm = [60, 0]\n");
  const std::string message = error_of(path);
  EXPECT_NE(message.find("markers[1].centre_mm"), std::string::npos) << message;
  EXPECT_NE(message.find("marker id 0"), std::string::npos) << message;
}

TEST(Target, DuplicateIdsAndMissingPoseMarkerAreRejected) {
  const std::string dup =
      write_temp("dup", kHeader +
                            "[[markers]]\nid = 0\nside_mm = 50\ncentre_mm = [0, 0]\n"
                            "[[markers]]\nid = 0\nside_mm = 50\ncentre_mm = [0, 90]\n");
  EXPECT_NE(error_of(dup).find("markers[1].id"), std::string::npos) << error_of(dup);
  const std::string nopose =
      write_temp("nopose",
                 "paper = \"A4\"\norigin_mm = [105, 148.5]\npose_marker = 3\n"
                 "[[markers]]\nid = 0\nside_mm = 50\ncentre_mm = [0, 0]\n");
  EXPECT_NE(error_of(nopose).find("pose_marker = 3"), std::string::npos) << error_of(nopose);
}

TEST(Target, SyntaxErrorNamesTheFileAndLine) {
  const std::string path = write_temp("syntax", "paper = \"A4\"\norigin_mm = [105, \n");
  const std::string message = error_of(path);
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("line"), std::string::npos) << message;
}

TEST(Target, MisspeltKeyIsRejected) {
  const std::string path = write_temp(
      "misspelt",
      kHeader + "quiet_cell = 2\n[[markers]]\nid = 0\nside_mm = 50\ncentre_mm = [0, 0]\n");
  EXPECT_EQ(error_of(path), path +
                                ": quiet_cell = 2: unknown key (misspelt?); expected one of name, "
                                "paper, sheet_width_mm, sheet_height_mm, origin_mm, pose_marker, "
                                "quiet_cells, family, markers");
  const std::string in_marker = write_temp(
      "misspelt_marker", kHeader + "[[markers]]\nid = 0\nside = 50\ncentre_mm = [0, 0]\n");
  EXPECT_EQ(error_of(in_marker),
            in_marker + ": markers[0].side_mm: missing; expected the marker side in mm > 0");
}

TEST(Target, ALayoutErrorIsAConfigError) {
  EXPECT_THROW(Target::load("/nonexistent/layout.toml"), config::ConfigError);
}

TEST(Target, CustomSheetNeedsItsSize) {
  const std::string path = write_temp("custom",
                                      "paper = \"custom\"\norigin_mm = [50, 50]\npose_marker = 0\n"
                                      "[[markers]]\nid = 0\nside_mm = 50\ncentre_mm = [0, 0]\n");
  EXPECT_NE(error_of(path).find("sheet_width_mm"), std::string::npos) << error_of(path);
  const std::string ok =
      write_temp("custom_ok",
                 "paper = \"custom\"\nsheet_width_mm = 100\nsheet_height_mm = 100\n"
                 "origin_mm = [50, 50]\npose_marker = 0\n"
                 "[[markers]]\nid = 0\nside_mm = 50\ncentre_mm = [0, 0]\n");
  const Target t = Target::load(ok);
  EXPECT_DOUBLE_EQ(t.sheet_width_m, 0.1);
  EXPECT_TRUE(t.sheet_origin_m.isApprox(Eigen::Vector2d(-0.05, -0.05)));
}

}  // namespace
}  // namespace vision
