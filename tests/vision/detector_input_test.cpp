// Detector inputs: image types and sizes it converts or ignores, parameters it
// refuses, and image files it cannot read (vision::read_image).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgproc.hpp>

#include "detector_frames.hpp"
#include "detector_synthetic.hpp"
#include "vision/detector.hpp"
#include "vision/detector_image.hpp"
#include "vision/image_codecs.hpp"

namespace {

namespace fs = std::filesystem;

// One frame of the paper's sheet, straight on at 0.45 m: all four markers in
// view, rendered once for the whole suite.
class DetectorInput : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    camera_ = new vision::Camera(vision::Camera::paper_default());
    codebook_ = new vision::Codebook();
    detector_test::SyntheticOptions o;
    o.supersampling = 2;
    const detector_test::SyntheticRenderer renderer(*camera_, vision::Target::paper_default(),
                                                    *codebook_, o);
    vision::Pose T;
    T.R = Eigen::Matrix3d(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
    T.t = Eigen::Vector3d(0.01, -0.005, 0.45);
    frame_ = new cv::Mat(renderer.render(T, 1));
  }
  static void TearDownTestSuite() {
    delete frame_;
    delete codebook_;
    delete camera_;
  }
  static std::vector<vision::Detection> detect(const cv::Mat& image) {
    return vision::Detector(*camera_, *codebook_).detect(image);
  }
  static fs::path temp_dir() {
    const fs::path dir = fs::path(::testing::TempDir()) / "detector_input_test";
    fs::create_directories(dir);
    return dir;
  }

  static vision::Camera* camera_;
  static vision::Codebook* codebook_;
  static cv::Mat* frame_;
};
vision::Camera* DetectorInput::camera_ = nullptr;
vision::Codebook* DetectorInput::codebook_ = nullptr;
cv::Mat* DetectorInput::frame_ = nullptr;

TEST_F(DetectorInput, FindsTheFourMarkersOfTheReferenceFrame) {
  const auto detections = detect(*frame_);
  ASSERT_EQ(detections.size(), 4u);
  for (int i = 0; i < 4; ++i)
    EXPECT_EQ(detections[i].id, i);
}

TEST_F(DetectorInput, BlankImageGivesNoDetections) {
  EXPECT_TRUE(detect(cv::Mat(571, 736, CV_8U, cv::Scalar(128))).empty());
  EXPECT_TRUE(detect(cv::Mat(571, 736, CV_8U, cv::Scalar(0))).empty());
  EXPECT_TRUE(detect(cv::Mat(571, 736, CV_8U, cv::Scalar(255))).empty());
}

TEST_F(DetectorInput, EmptyAndOnePixelImagesGiveNoDetections) {
  EXPECT_TRUE(detect(cv::Mat()).empty());
  EXPECT_TRUE(detect(cv::Mat(1, 1, CV_8U, cv::Scalar(0))).empty());
  EXPECT_TRUE(detect(cv::Mat(1, 1, CV_16U, cv::Scalar(4000))).empty());
  EXPECT_TRUE(detect(cv::Mat(1, 1, CV_8UC3, cv::Scalar(1, 2, 3))).empty());
}

// A grey image stored as BGR converts back to exactly the same grey levels
// (the BT.601 weights sum to 1), so the detections are identical.
TEST_F(DetectorInput, ColourImageGivesTheSameDetectionsAsGrey) {
  cv::Mat bgr, bgra;
  cv::cvtColor(*frame_, bgr, cv::COLOR_GRAY2BGR);
  cv::cvtColor(*frame_, bgra, cv::COLOR_GRAY2BGRA);
  const auto grey = detect(*frame_);
  for (const cv::Mat& colour : {bgr, bgra}) {
    const auto d = detect(colour);
    ASSERT_EQ(d.size(), grey.size());
    for (size_t i = 0; i < d.size(); ++i) {
      EXPECT_EQ(d[i].id, grey[i].id);
      for (int k = 0; k < 4; ++k)
        EXPECT_EQ(d[i].corners_px[k], grey[i].corners_px[k]);
    }
  }
}

// A 12-bit camera in a 16-bit container (values x 16): scaled by its maximum,
// it maps back to the 8-bit levels within one level of rounding, which moves
// an edge by at most (1 level / contrast ~170 levels) x (edge width ~2 px),
// about 0.01 px.
TEST_F(DetectorInput, SixteenBitImageIsScaledToItsRange) {
  cv::Mat wide;
  frame_->convertTo(wide, CV_16U, 16.0);
  const auto grey = detect(*frame_);
  const auto d = detect(wide);
  ASSERT_EQ(d.size(), grey.size());
  for (size_t i = 0; i < d.size(); ++i) {
    EXPECT_EQ(d[i].id, grey[i].id);
    for (int k = 0; k < 4; ++k)
      EXPECT_LT((d[i].corners_px[k] - grey[i].corners_px[k]).norm(), 0.02);
  }
}

TEST_F(DetectorInput, FloatImageInUnitRangeIsDetected) {
  cv::Mat f;
  frame_->convertTo(f, CV_32F, 1.0 / 255);
  EXPECT_EQ(detect(f).size(), 4u);
}

TEST_F(DetectorInput, TwoChannelImageIsRefusedNamingTheChannels) {
  try {
    detect(cv::Mat(10, 10, CV_8UC2));
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "image with 2 channels (expected 1 grey, 3 BGR or 4 BGRA)");
  }
}

TEST_F(DetectorInput, OutOfRangeParameterIsRefusedByName) {
  vision::DetectorParameters p;
  p.edge_refine_px = p.edge_search_px + 1;
  try {
    vision::Detector(*camera_, *codebook_, p);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "detector parameter edge_refine_px: expected in [1, edge_search_px]");
  }
}

void write_bytes(const fs::path& path, const std::vector<uchar>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

std::string read_error(const fs::path& path) {
  try {
    vision::read_image(path.string());
  } catch (const vision::ImageError& e) {
    return e.what();
  }
  return "no error";
}

TEST_F(DetectorInput, ReadImageNamesAMissingFile) {
  const fs::path p = temp_dir() / "missing.png";
  EXPECT_EQ(read_error(p), "image '" + p.string() + "': cannot be opened (missing or unreadable)");
}

TEST_F(DetectorInput, ReadImageNamesAnEmptyFile) {
  const fs::path p = temp_dir() / "empty.png";
  write_bytes(p, {});
  EXPECT_EQ(read_error(p), "image '" + p.string() + "': is empty (0 bytes)");
}

TEST_F(DetectorInput, ReadImageNamesTruncatedPngAndJpeg) {
  for (const std::string ext : {".png", ".jpg"}) {
    std::vector<uchar> bytes;
    ASSERT_TRUE(vision::imencode(ext, *frame_, bytes));
    bytes.resize(bytes.size() / 2);
    const fs::path p = temp_dir() / ("truncated" + ext);
    write_bytes(p, bytes);
    const std::string format = ext == ".png" ? "PNG" : "JPEG";
    EXPECT_EQ(read_error(p), "image '" + p.string() + "': is truncated (" + format +
                                 " data ends before its end marker)");
  }
}

TEST_F(DetectorInput, ReadImageNamesAFileThatIsNotAnImage) {
  const fs::path p = temp_dir() / "notes.png";
  const std::string text = "camera calibration notes, not an image\n";
  write_bytes(p, std::vector<uchar>(text.begin(), text.end()));
  EXPECT_EQ(read_error(p), "image '" + p.string() +
                               "': is not an image rig reads (expected PNG, JPEG, TIFF, "
                               "PGM/PPM or BMP)");
}

TEST_F(DetectorInput, ReadImageKeepsSixteenBitsAndColour) {
  cv::Mat wide, bgr;
  frame_->convertTo(wide, CV_16U, 16.0);
  cv::cvtColor(*frame_, bgr, cv::COLOR_GRAY2BGR);
  const fs::path p16 = temp_dir() / "wide.png", pc = temp_dir() / "colour.png";
  ASSERT_TRUE(vision::imwrite(p16.string(), wide));
  ASSERT_TRUE(vision::imwrite(pc.string(), bgr));
  const cv::Mat r16 = vision::read_image(p16.string());
  EXPECT_EQ(r16.type(), CV_16UC1);
  EXPECT_EQ(detect(r16).size(), 4u);
  const cv::Mat rc = vision::read_image(pc.string());
  EXPECT_EQ(rc.type(), CV_8UC3);
  EXPECT_EQ(detect(rc).size(), 4u);
}

}  // namespace
