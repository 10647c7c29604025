// vision::Camera against OpenCV's own lens model, and the calibration loaders
// on files written by OpenCV's FileStorage and in ROS camera_info form.
#include "vision/camera.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;

// A grid of camera-frame points whose projections cover the image and a
// margin beyond it, at the paper's depths.
std::vector<cv::Point3d> grid_points(const vision::Camera& cam) {
  std::vector<cv::Point3d> pts;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.1, 1.1), z(0.1, 1.0);
  const auto& k = cam.intrinsics();
  for (int i = 0; i < 2000; ++i) {
    const double depth = z(rng);
    const double px = u(rng) * cam.width_px(), py = u(rng) * cam.height_px();
    pts.emplace_back((px - k.cx) / k.fx * depth, (py - k.cy) / k.fy * depth, depth);
  }
  return pts;
}

TEST(Camera, ProjectMatchesCvProjectPointsTo1e9Px) {
  const auto cam = vision::Camera::paper_default();
  const auto pts = grid_points(cam);
  std::vector<cv::Point2d> expected;
  cv::projectPoints(pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cam.camera_matrix_cv(),
                    cam.distortion_cv(), expected);
  for (size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector2d px = cam.project({pts[i].x, pts[i].y, pts[i].z});
    // Both evaluate the same polynomial in double precision: differences are
    // rounding, ~1e-13 px at these magnitudes.
    EXPECT_NEAR(px.x(), expected[i].x, 1e-9);
    EXPECT_NEAR(px.y(), expected[i].y, 1e-9);
  }
}

// Undistorts a grid of pixels `step` apart, with an offset off the pixel
// centres, and compares with cv::undistortPoints asked to run to
// convergence (OpenCV's default stops after 5 fixed-point steps): both invert
// the same model, so they agree to rounding, compared on the image (normalized
// differences scaled by the focal length); the round trip lands on the pixel
// within the stated tolerance.
void expect_undistort_matches_opencv(const vision::Camera& cam, int step) {
  std::vector<cv::Point2d> pixels;
  for (int v = 0; v < cam.height_px(); v += step)
    for (int u = 0; u < cam.width_px(); u += step)
      pixels.emplace_back(u + 0.37, v + 0.81);
  std::vector<cv::Point2d> expected;
  cv::undistortPoints(
      pixels, expected, cam.camera_matrix_cv(), cam.distortion_cv(), cv::noArray(), cv::noArray(),
      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 1000, 1e-16));
  const auto& k = cam.intrinsics();
  for (size_t i = 0; i < pixels.size(); ++i) {
    Eigen::Vector2d xy;
    ASSERT_TRUE(cam.undistort_point({pixels[i].x, pixels[i].y}, &xy));
    EXPECT_NEAR(k.fx * xy.x(), k.fx * expected[i].x, 1e-9);
    EXPECT_NEAR(k.fy * xy.y(), k.fy * expected[i].y, 1e-9);
    EXPECT_LE((cam.distort_normalized(xy) - Eigen::Vector2d(pixels[i].x, pixels[i].y)).norm(),
              vision::Camera::kUndistortTolerancePx);
  }
}

// The distortion Jacobian against central differences at two points.
// Truncation ~h^2 * f ~ 1e-11, rounding ~1e-16 * 700 / h ~ 1e-6 px: 1e-5.
void expect_distort_jacobian_matches_finite_differences(const vision::Camera& cam) {
  const double h = 1e-7;
  for (const Eigen::Vector2d& xy : {Eigen::Vector2d(0.3, -0.2), Eigen::Vector2d(-0.5, 0.35)}) {
    const Eigen::Matrix2d J = cam.distort_jacobian(xy);
    for (int k = 0; k < 2; ++k) {
      Eigen::Vector2d d = Eigen::Vector2d::Zero();
      d(k) = h;
      const Eigen::Vector2d numeric =
          (cam.distort_normalized(xy + d) - cam.distort_normalized(xy - d)) / (2 * h);
      EXPECT_NEAR(J(0, k), numeric.x(), 1e-5);
      EXPECT_NEAR(J(1, k), numeric.y(), 1e-5);
    }
  }
}

TEST(Camera, UndistortMatchesCvUndistortPointsTo1e9Px) {
  expect_undistort_matches_opencv(vision::Camera::paper_default(), 10);
}

TEST(Camera, DistortJacobianMatchesFiniteDifferences) {
  expect_distort_jacobian_matches_finite_differences(vision::Camera::paper_default());
}

// The paper's camera with thin-prism terms ten times those of the simulated
// `lab` lens (config/realism/lab.toml), so that a term left out or with a
// wrong sign moves a corner pixel by far more than the tolerances below.
vision::Camera thin_prism_camera() {
  const auto ref = vision::Camera::paper_default();
  vision::Distortion d = ref.distortion();
  d.s1 = 1e-3;
  d.s2 = -5e-4;
  d.s3 = -8e-4;
  d.s4 = 3e-4;
  return vision::Camera(ref.intrinsics(), d, ref.width_px(), ref.height_px());
}

TEST(Camera, ThinPrismProjectMatchesCvProjectPointsWithTwelveCoefficients) {
  const auto cam = thin_prism_camera();
  ASSERT_EQ(cam.distortion_cv().cols, 12);  // OpenCV's k1 k2 p1 p2 k3 k4 k5 k6 s1 s2 s3 s4
  const auto pts = grid_points(cam);
  std::vector<cv::Point2d> expected;
  cv::projectPoints(pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cam.camera_matrix_cv(),
                    cam.distortion_cv(), expected);
  double prism_shift = 0;  // how far the thin prism moves the farthest point, px
  const auto plain = vision::Camera::paper_default();
  for (size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector2d px = cam.project({pts[i].x, pts[i].y, pts[i].z});
    // The same polynomial in double precision: differences are rounding.
    EXPECT_NEAR(px.x(), expected[i].x, 1e-9);
    EXPECT_NEAR(px.y(), expected[i].y, 1e-9);
    prism_shift =
        std::max(prism_shift, (px - plain.project({pts[i].x, pts[i].y, pts[i].z})).norm());
  }
  // At the image corner r2 ~ 0.44: s1 r2 fx ~ 0.3 px, so the comparison
  // above would see a missing term by eight orders of magnitude.
  EXPECT_GT(prism_shift, 0.2);
}

TEST(Camera, ThinPrismUndistortMatchesCvUndistortPoints) {
  expect_undistort_matches_opencv(thin_prism_camera(), 15);
}

// A missing prism term would put the Jacobian off by 2 s1 x fx ~ 0.4 px.
TEST(Camera, ThinPrismDistortJacobianMatchesFiniteDifferences) {
  expect_distort_jacobian_matches_finite_differences(thin_prism_camera());
}

class CalibrationFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    // Process id and test name: no other test process writes this folder.
    dir_ = fs::temp_directory_path() /
           ("rig_calib_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(path(name)) << text;
  }
  fs::path dir_;
};

// What OpenCV's calibration sample writes: FileStorage with these keys.
void write_opencv_calibration(const std::string& file, const cv::Mat& K, const cv::Mat& D) {
  cv::FileStorage fs(file, cv::FileStorage::WRITE);
  fs << "calibration_time"
     << "2026-11-22"
     << "image_width" << 736 << "image_height" << 571;
  fs << "camera_matrix" << K << "distortion_coefficients" << D << "avg_reprojection_error" << 0.21;
}

TEST_F(CalibrationFiles, LoadsOpenCvYamlAndXmlWrittenByFileStorage) {
  const auto ref = vision::Camera::paper_default();
  for (const std::string& name : {std::string("calib.yaml"), std::string("calib.xml")}) {
    write_opencv_calibration(path(name), ref.camera_matrix_cv(), ref.distortion_cv().t());
    const auto cam = vision::Camera::load(path(name));
    EXPECT_EQ(cam.width_px(), 736);
    EXPECT_EQ(cam.height_px(), 571);
    EXPECT_DOUBLE_EQ(cam.intrinsics().fy, 731.1);
    EXPECT_DOUBLE_EQ(cam.intrinsics().cx, 388.0);
    EXPECT_DOUBLE_EQ(cam.distortion().k1, -0.2279);
    EXPECT_DOUBLE_EQ(cam.distortion().p2, 0.0006245);
  }
}

TEST_F(CalibrationFiles, LoadsEightCoefficientFilesWhenTheRationalTermsAreZero) {
  const auto ref = vision::Camera::paper_default();
  cv::Mat D = cv::Mat::zeros(1, 8, CV_64F);
  ref.distortion_cv().copyTo(D.colRange(0, 5));
  write_opencv_calibration(path("c.yml"), ref.camera_matrix_cv(), D);
  EXPECT_DOUBLE_EQ(vision::Camera::load(path("c.yml")).distortion().k2, 0.1479);
  D.at<double>(0, 6) = 0.01;
  write_opencv_calibration(path("c.yml"), ref.camera_matrix_cv(), D);
  EXPECT_THROW(vision::Camera::load(path("c.yml")), vision::CalibrationError);
}

TEST_F(CalibrationFiles, LoadsRosCameraInfoYaml) {
  write("ros.yaml", R"(image_width: 640
image_height: 480
camera_name: narrow_stereo
camera_matrix:
  rows: 3
  cols: 3
  data: [600.5, 0, 320.25, 0, 601.75, 240.5, 0, 0, 1]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.1, 0.01, 0.001, -0.002, 0.0005]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]
)");
  const auto cam = vision::Camera::load(path("ros.yaml"));
  EXPECT_EQ(cam.width_px(), 640);
  EXPECT_DOUBLE_EQ(cam.intrinsics().fx, 600.5);
  EXPECT_DOUBLE_EQ(cam.intrinsics().cy, 240.5);
  EXPECT_DOUBLE_EQ(cam.distortion().p1, 0.001);
  EXPECT_DOUBLE_EQ(cam.distortion().k3, 0.0005);
}

void expect_error(const std::string& file, const std::string& words) {
  try {
    vision::Camera::load(file);
    FAIL() << "expected CalibrationError with '" << words << "'";
  } catch (const vision::CalibrationError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(file), std::string::npos) << what;
    EXPECT_NE(what.find(words), std::string::npos) << what;
  }
}

TEST_F(CalibrationFiles, MissingFileNamesTheFile) {
  expect_error(path("nope.yaml"), "cannot be opened");
}

// OpenCV 4.6's XML reader dereferences a null pointer on a NUL byte inside a
// tag (the input libFuzzer found, cut to its cause); the loader refuses any
// control byte before OpenCV sees the file.
TEST_F(CalibrationFiles, ControlByteIsRefusedBeforeOpenCvParsesIt) {
  const std::string xml =
      std::string("<?xml version=\"1.0\"?>\n<opencv_storage>\n<image_width>736</image_width>\n") +
      "<distortion_coefficients type_id=" + std::string(1, '\0') +
      "&pencv-matrix\"><rows>1</rows></distortion_coefficients>\n</opencv_storage>\n";
  std::ofstream(path("nul.xml"), std::ios::binary) << xml;
  expect_error(path("nul.xml"), "line 4: holds the control byte 0x00");
}

// OpenCV 4.6's XML reader reads past the end of the file's buffer when the
// file ends inside a tag, after an attribute's '=' (the input libFuzzer found
// in a 10-minute run of scripts/fuzz calibration; under ASan a SEGV): the
// loader refuses a tag that is never closed, naming its line, before OpenCV
// sees the file. Both an attribute cut after '=' and one cut before it.
TEST_F(CalibrationFiles, TagTheFileEndsInsideOfIsRefusedBeforeOpenCvParsesIt) {
  write("cut.xml", "<?xml version=\"1.0\"?>\n<opencv_storaa111111 venirsocoeffi=");
  expect_error(path("cut.xml"), "line 2: the file ends inside a tag; expected '>'");
  write("cut2.xml", "<?xml version=\"1.0\"?>\n<opencv_storage>\n<image_width type_id");
  expect_error(path("cut2.xml"), "line 3: the file ends inside a tag; expected '>'");
}

// OpenCV allocates the matrix a file declares before reading its data: a
// declared 100000 x 100000 matrix asked for 80 GB (found by libFuzzer).
TEST_F(CalibrationFiles, HugeDeclaredMatrixIsRefusedBeforeOpenCvAllocatesIt) {
  write("huge.yaml",
        "%YAML:1.0\n---\nimage_width: 736\nimage_height: 571\n"
        "camera_matrix: !!opencv-matrix\n   rows: 100000\n   cols: 100000\n   dt: d\n"
        "   data: [ 706.1, 0, 388.0, 0, 731.1, 269.6, 0, 0, 1 ]\n");
  expect_error(path("huge.yaml"), "key 'camera_matrix'");
  expect_error(path("huge.yaml"), "declares rows x cols = 100000x100000; expected 1 to 16");
}

// The input libFuzzer found (scripts/fuzz calibration): a line that is not
// KEY: VALUE inside an !!opencv-matrix block. OpenCV 4.6's YAML reader throws
// std::length_error on it (not a cv::Exception), which ended the process;
// rig's own reader of the calibration subset refuses it, naming the line.
const char* const kMatrixWithAStrayLine =
    "%YAML:1.0\n---\nimage_width: 736\nimage_height: 571\ncamera_matrix: !!opencv-matrix\n"
    "   rows: 3\n   cols: 3\n   dt: d\n   :d td\n"
    "   data: [ 706.1, 0., 388.0, 0., 731.1, 269.6, 0., 0., 1. ]\n";

TEST_F(CalibrationFiles, AStrayLineInAnOpenCvMatrixIsRefusedNamingTheLine) {
  write("stray.yaml", kMatrixWithAStrayLine);
  expect_error(path("stray.yaml"), "line 9: ':d td' is not KEY: VALUE; expected KEY: VALUE");
}

// The same bytes named .xml (the fuzz target's other half): OpenCV picks its
// parser by the first bytes, so this reached the same YAML parser. The
// format is what the file holds: it is read, and refused, as YAML.
TEST_F(CalibrationFiles, YamlNamedXmlIsReadAsYaml) {
  write("stray.xml", kMatrixWithAStrayLine);
  expect_error(path("stray.xml"), "line 9: ':d td' is not KEY: VALUE");
  write("good.xml",
        "image_width: 640\nimage_height: 480\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: [600, "
        "0, 320, 0, 600, 240, 0, 0, 1]\ndistortion_coefficients: [0, 0, 0, 0]\n");
  EXPECT_EQ(vision::Camera::load(path("good.xml")).width_px(), 640);
}

// ROS camera_info in flow style, as docs/target-and-geometry.md shows it and
// as many tools write it: {rows, cols, data} on one line or over several.
TEST_F(CalibrationFiles, RosFlowMappingsAreRead) {
  write("flow.yaml",
        "image_width: 640\nimage_height: 480\n"
        "camera_matrix: {rows: 3, cols: 3, data: [600, 0, 320, 0, 610, 240, 0, 0, 1]}\n"
        "distortion_model: plumb_bob\n"
        "distortion_coefficients: {rows: 1, cols: 5,\n  data: [-0.2, 0.1, 0, 0, 0]}\n");
  const vision::Camera cam = vision::Camera::load(path("flow.yaml"));
  EXPECT_EQ(cam.intrinsics().fy, 610);
  EXPECT_EQ(cam.distortion().k1, -0.2);
}

// Only the YAML that calibrations use is read; anything else is refused
// with the line and what was expected, never handed to a general parser.
TEST_F(CalibrationFiles, YamlOutsideTheCalibrationSubsetIsRefusedNamingTheLine) {
  const std::string head = "image_width: 640\nimage_height: 480\n";
  const std::string matrix = "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {head + "camera_matrix:\n\trows: 3\n", "line 4: a tab in the indentation"},
      {head + "camera_matrix:\n  - 1\n  - 2\n", "line 4: a block sequence item '- 1'"},
      {head + "camera_matrix: {rows: 3, cols: 3\n", "line 3: a mapping '{' with no closing '}'"},
      {head + "camera_matrix: {rows: {a: 1}}\n", "line 3: '}' after the mapping"},
      {head + "camera_matrix: {rows: 3} x\n", "line 3: 'x' after the mapping"},
      {head + "camera_matrix: &m [1, 2]\n", "line 3: '&' (an anchor"},
      {head + "camera_matrix: !!binary abc\n", "line 3: the tag '!!binary'"},
      {head + "image_width: 641\n", "line 3: key 'image_width' given twice"},
      {head + matrix + "  data: [1, 0, 0,\n    0, 1, 0\n",
       "line 7: a sequence '[' with no closing"},
      {head + matrix + "  data: [1, [0], 0]\n", "line 7: a collection inside a sequence"},
      {head + matrix + "  data: [1, , 0]\n", "line 7: an empty item"},
      {head + matrix + "   data: [1]\n", "line 7: indented 3 columns in a block indented 2"},
      {head + "a:\n b:\n  c:\n   d:\n    e:\n     f:\n      g:\n       h:\n        i: 1\n",
       "line 11: blocks nested more than 8 levels deep"},
      {head + "---\nimage_width: 1\n", "line 3: a second YAML document"},
      {head + "camera_name: \"narrow\n", "line 3: a quoted string not closed on its line"},
      {"%YAML:2.0\n" + head, "line 1: the directive '%YAML:2.0'"},
      {"  " + head, "line 1: the first key is indented"},
      {"# only a comment\n", "line 2: no KEY: VALUE line"},
      {head + "camera_matrix: a: b\n", "line 3: a second ':' in 'a: b'"},
  };
  for (const auto& [text, words] : cases) {
    write("subset.yaml", text);
    SCOPED_TRACE(text);
    expect_error(path("subset.yaml"), words);
  }
}

// What OpenCV and ROS tools write beyond the four keys (comments, quoted
// strings, a sequence over several lines, dt f) still reads.
TEST_F(CalibrationFiles, ReadsCommentsQuotedTextMultiLineDataAndFloatMatrices) {
  write(
      "full.yaml",
      "%YAML:1.0\n---\n# calibrated 2026-11-22\ncalibration_time: \"Sun 22 Nov # not a comment\"\n"
      "camera_name: 'it''s the bench camera'\nimage_width: 736   # px\nimage_height: 571\n"
      "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: f\n"
      "   data: [ 7.0610000000000002e+02, 0., 388.,   # fx, skew, cx\n"
      "       0., 7.3110000000000002e+02, 2.6960000000000002e+02,\n       0., 0., 1. ]\n"
      "distortion_coefficients: !!opencv-matrix\n   rows: 5\n   cols: 1\n   dt: d\n"
      "   data: [ -2.2789999999999999e-01, 1.4790000000000000e-01,\n"
      "       -7.9849999999999995e-04, 6.2449999999999995e-04, 0. ]\n"
      "avg_reprojection_error: 2.0999999999999999e-01\n");
  const auto cam = vision::Camera::load(path("full.yaml"));
  EXPECT_EQ(cam.width_px(), 736);
  // dt f: the values OpenCV would hold, rounded to float.
  EXPECT_EQ(cam.intrinsics().fy, static_cast<double>(731.1f));
  EXPECT_DOUBLE_EQ(cam.distortion().p2, 0.0006245);
}

TEST_F(CalibrationFiles, MissingKeyNamesTheKey) {
  cv::FileStorage fs(path("k.yaml"), cv::FileStorage::WRITE);
  fs << "image_width" << 736 << "image_height" << 571 << "camera_matrix"
     << vision::Camera::paper_default().camera_matrix_cv();
  fs.release();
  expect_error(path("k.yaml"), "key 'distortion_coefficients' is missing");
}

TEST_F(CalibrationFiles, MalformedMatrixNamesTheKeyAndShape) {
  write_opencv_calibration(path("m.yaml"), cv::Mat::eye(2, 3, CV_64F),
                           vision::Camera::paper_default().distortion_cv());
  expect_error(path("m.yaml"), "key 'camera_matrix' must be 3x3, got 2x3");
}

TEST_F(CalibrationFiles, RosDataCountMismatchNamesTheKey) {
  write("bad.yaml",
        "image_width: 640\nimage_height: 480\ncamera_matrix:\n  rows: 3\n  cols: 3\n"
        "  data: [1, 0, 0, 0, 1]\ndistortion_coefficients:\n  rows: 1\n  cols: 5\n"
        "  data: [0, 0, 0, 0, 0]\n");
  expect_error(path("bad.yaml"), "key 'camera_matrix' has 5 values but rows x cols = 3x3");
}

TEST_F(CalibrationFiles, SaveThenLoadRoundTrips) {
  const auto ref = vision::Camera::paper_default();
  ref.save(path("out.yaml"));
  const auto back = vision::Camera::load(path("out.yaml"));
  EXPECT_DOUBLE_EQ(back.intrinsics().fx, ref.intrinsics().fx);
  EXPECT_DOUBLE_EQ(back.distortion().p1, ref.distortion().p1);
  EXPECT_EQ(back.height_px(), ref.height_px());
}

TEST_F(CalibrationFiles, ThinPrismRoundTripsThroughTwelveCoefficients) {
  const auto ref = thin_prism_camera();
  ref.save(path("prism.yaml"));
  // What the file holds is what OpenCV reads: 12 coefficients in its order.
  cv::FileStorage fs(path("prism.yaml"), cv::FileStorage::READ);
  cv::Mat D;
  fs["distortion_coefficients"] >> D;
  ASSERT_EQ(D.total(), 12u);
  EXPECT_EQ(D.at<double>(8), 1e-3);
  EXPECT_EQ(D.at<double>(11), 3e-4);
  const auto back = vision::Camera::load(path("prism.yaml"));
  EXPECT_EQ(back.distortion().s1, ref.distortion().s1);
  EXPECT_EQ(back.distortion().s2, ref.distortion().s2);
  EXPECT_EQ(back.distortion().s3, ref.distortion().s3);
  EXPECT_EQ(back.distortion().s4, ref.distortion().s4);
  EXPECT_EQ(back.distortion().k1, ref.distortion().k1);
  // A camera without thin prism keeps the 5-coefficient file.
  vision::Camera::paper_default().save(path("plain.yaml"));
  cv::FileStorage plain(path("plain.yaml"), cv::FileStorage::READ);
  plain["distortion_coefficients"] >> D;
  EXPECT_EQ(D.total(), 5u);
}

TEST_F(CalibrationFiles, ReadsThinPrismFromFourteenCoefficientsAndRefusesWhatItCannotHold) {
  const auto ref = vision::Camera::paper_default();
  cv::Mat D = cv::Mat::zeros(1, 14, CV_64F);
  ref.distortion_cv().copyTo(D.colRange(0, 5));
  D.at<double>(0, 10) = -5e-5;  // s3
  write_opencv_calibration(path("c.yml"), ref.camera_matrix_cv(), D);
  EXPECT_EQ(vision::Camera::load(path("c.yml")).distortion().s3, -5e-5);
  D.at<double>(0, 13) = 1e-3;  // tau_y
  write_opencv_calibration(path("c.yml"), ref.camera_matrix_cv(), D);
  expect_error(path("c.yml"), "non-zero sensor tilt tau");
  D = cv::Mat::zeros(1, 12, CV_64F);
  D.at<double>(0, 5) = 0.01;  // k4
  write_opencv_calibration(path("c.yml"), ref.camera_matrix_cv(), D);
  expect_error(path("c.yml"), "non-zero rational term k4");
  write_opencv_calibration(path("c.yml"), ref.camera_matrix_cv(), cv::Mat::zeros(1, 6, CV_64F));
  expect_error(path("c.yml"), "must be a vector of 4, 5, 8, 12 or 14 values");
}

}  // namespace
