// vision::MarkerFamily: each family's cells, rasterised, are read back with
// the right id by that family's own detector (rig's Detector for rig4x4,
// cv::aruco::detectMarkers for ArUco, apriltag_detector_detect for AprilTag),
// so the bit layouts taken from the libraries are the libraries' own.
#include "vision/marker_family.hpp"

#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag36h11.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include "vision/artwork.hpp"
#include "vision/camera.hpp"
#include "vision/codebook.hpp"
#include "vision/detector.hpp"
#include "vision/image_codecs.hpp"

namespace vision {
namespace {

// Marker `id` drawn axis-aligned, `px` pixels per cell, centred in a white
// camera-sized image (so rig's detector, which models that camera, sees
// sides far from the image border and distortion). Exact cell edges: each
// pixel is wholly one cell, no interpolation, no noise.
cv::Mat raster(const MarkerFamily& family, int id, int px, cv::Size size) {
  cv::Mat image(size, CV_8UC1, cv::Scalar(255));
  const int n = family.marker_cells();
  const int x0 = (size.width - n * px) / 2, y0 = (size.height - n * px) / 2;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c)
      if (!family.cell_is_white(id, r, c))
        image(cv::Rect(x0 + c * px, y0 + r * px, px, px)).setTo(0);
  return image;
}

// Rig's detector models the camera of the image: a distortion-free one of the
// image's size for a scanned sheet (a flat raster has no lens).
std::vector<int> detect_rig(const cv::Mat& image) {
  const Camera camera = image.size() == cv::Size(Camera::paper_default().width_px(),
                                                 Camera::paper_default().height_px())
                            ? Camera::paper_default()
                            : Camera(Intrinsics{1000, 1000, image.cols / 2.0, image.rows / 2.0},
                                     Distortion{}, image.cols, image.rows);
  const Detector detector(camera, Codebook());
  std::vector<int> ids;
  for (const Detection& d : detector.detect(image))
    ids.push_back(d.id);
  return ids;
}

std::vector<int> detect_aruco(const cv::Mat& image, cv::aruco::PREDEFINED_DICTIONARY_NAME name) {
  std::vector<int> ids;
  std::vector<std::vector<cv::Point2f>> corners;
  cv::aruco::detectMarkers(image, cv::aruco::getPredefinedDictionary(name), corners, ids);
  return ids;
}

std::vector<int> detect_apriltag(const cv::Mat& image, apriltag_family_t* family) {
  apriltag_detector_t* detector = apriltag_detector_create();
  apriltag_detector_add_family(detector, family);
  detector->nthreads = 1;
  image_u8_t view{image.cols, image.rows, static_cast<int>(image.step), image.data};
  zarray_t* found = apriltag_detector_detect(detector, &view);
  std::vector<int> ids;
  for (int i = 0; i < zarray_size(found); ++i) {
    apriltag_detection_t* d = nullptr;
    zarray_get(found, i, &d);
    ids.push_back(d->id);
  }
  apriltag_detections_destroy(found);
  apriltag_detector_destroy(detector);
  return ids;
}

// Ids checked per family: the first, second, a middle one and the last (the
// byte/bit order errors this catches would scramble every id, and a transposed
// or mirrored grid is no valid code in these families).
std::vector<int> sample_ids(const MarkerFamily& f) {
  return {0, 1, f.size() / 2, f.size() - 1};
}

void expect_read_back(const std::string& name,
                      const std::function<std::vector<int>(const cv::Mat&)>& detect) {
  const MarkerFamily& family = MarkerFamily::named(name);
  const cv::Size size(Camera::paper_default().width_px(), Camera::paper_default().height_px());
  for (const int id : sample_ids(family)) {
    // 20 px cells: a 120-160 px marker, well within every detector's range.
    EXPECT_EQ(detect(raster(family, id, 20, size)), std::vector<int>{id}) << name << " id " << id;
  }
}

TEST(MarkerFamily, KnownFamiliesHaveTheLibrariesSizes) {
  struct Row {
    const char* name;
    int code_cells, size;
  };
  for (const Row& row :
       {Row{"rig4x4", 4, 35}, Row{"aruco:DICT_4X4_50", 4, 50}, Row{"aruco:DICT_6X6_250", 6, 250},
        Row{"aruco:DICT_APRILTAG_36h11", 6, 587}, Row{"apriltag:tag36h11", 6, 587},
        Row{"apriltag:tag16h5", 4, 30}}) {
    const MarkerFamily& f = MarkerFamily::named(row.name);
    EXPECT_EQ(f.name(), row.name);
    EXPECT_EQ(f.code_cells(), row.code_cells) << row.name;
    EXPECT_EQ(f.border_cells(), 1) << row.name;
    EXPECT_EQ(f.marker_cells(), row.code_cells + 2) << row.name;
    EXPECT_EQ(f.size(), row.size) << row.name;
  }
  EXPECT_EQ(MarkerFamily::names().front(), MarkerFamily::kDefaultName);
}

TEST(MarkerFamily, Rig4x4IsTheCodebook) {
  const Codebook codebook;
  const MarkerFamily& f = MarkerFamily::named("rig4x4");
  for (int id = 0; id < f.size(); ++id)
    for (int r = 0; r < kMarkerCells; ++r)
      for (int c = 0; c < kMarkerCells; ++c)
        ASSERT_EQ(f.cell_is_white(id, r, c),
                  Codebook::marker_cell_is_white(codebook.code(id), r, c));
}

TEST(MarkerFamily, UnknownNameAndIdAreRefusedWithTheAcceptedValues) {
  try {
    MarkerFamily::named("aruco:DICT_5X5_100");
    FAIL() << "accepted an unknown family";
  } catch (const MarkerFamilyError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("\"aruco:DICT_5X5_100\""), std::string::npos) << what;
    for (const std::string& n : MarkerFamily::names())
      EXPECT_NE(what.find(n), std::string::npos) << what;
  }
  const MarkerFamily& f = MarkerFamily::named("apriltag:tag16h5");
  EXPECT_NO_THROW(f.check_id(29));
  EXPECT_THROW(f.check_id(30), MarkerFamilyError);
  EXPECT_THROW(f.check_id(-1), MarkerFamilyError);
}

TEST(MarkerFamily, Rig4x4ReadsBackWithRigsDetector) {
  expect_read_back("rig4x4", detect_rig);
}

TEST(MarkerFamily, ArucoDictionariesReadBackWithCvAruco) {
  expect_read_back("aruco:DICT_4X4_50",
                   [](const cv::Mat& im) { return detect_aruco(im, cv::aruco::DICT_4X4_50); });
  expect_read_back("aruco:DICT_6X6_250",
                   [](const cv::Mat& im) { return detect_aruco(im, cv::aruco::DICT_6X6_250); });
  expect_read_back("aruco:DICT_APRILTAG_36h11", [](const cv::Mat& im) {
    return detect_aruco(im, cv::aruco::DICT_APRILTAG_36h11);
  });
}

TEST(MarkerFamily, AprilTagFamiliesReadBackWithApriltag) {
  std::unique_ptr<apriltag_family_t, void (*)(apriltag_family_t*)> tag36(tag36h11_create(),
                                                                         tag36h11_destroy);
  std::unique_ptr<apriltag_family_t, void (*)(apriltag_family_t*)> tag16(tag16h5_create(),
                                                                         tag16h5_destroy);
  expect_read_back("apriltag:tag36h11",
                   [&](const cv::Mat& im) { return detect_apriltag(im, tag36.get()); });
  expect_read_back("apriltag:tag16h5",
                   [&](const cv::Mat& im) { return detect_apriltag(im, tag16.get()); });
}

// A printed sheet of each family (the paper's four-marker layout, PNG at
// 100 dpi: 50 mm markers of about 197 px) holds its four markers: the
// family's own detector finds exactly ids 0-3 on it.
TEST(MarkerFamily, PrintedTargetOfEachFamilyHoldsItsFourMarkers) {
  std::unique_ptr<apriltag_family_t, void (*)(apriltag_family_t*)> tag36(tag36h11_create(),
                                                                         tag36h11_destroy);
  std::unique_ptr<apriltag_family_t, void (*)(apriltag_family_t*)> tag16(tag16h5_create(),
                                                                         tag16h5_destroy);
  const std::map<std::string, std::function<std::vector<int>(const cv::Mat&)>> detectors = {
      {"rig4x4", detect_rig},
      {"aruco:DICT_4X4_50",
       [](const cv::Mat& im) { return detect_aruco(im, cv::aruco::DICT_4X4_50); }},
      {"aruco:DICT_6X6_250",
       [](const cv::Mat& im) { return detect_aruco(im, cv::aruco::DICT_6X6_250); }},
      {"aruco:DICT_APRILTAG_36h11",
       [](const cv::Mat& im) { return detect_aruco(im, cv::aruco::DICT_APRILTAG_36h11); }},
      {"apriltag:tag36h11", [&](const cv::Mat& im) { return detect_apriltag(im, tag36.get()); }},
      {"apriltag:tag16h5", [&](const cv::Mat& im) { return detect_apriltag(im, tag16.get()); }}};
  for (const std::string& name : MarkerFamily::names()) {
    Target target = Target::paper_default();
    target.family = name;
    const std::string path =
        (std::filesystem::temp_directory_path() / "rig_marker_family_target.png").string();
    write_target_artwork(target, TargetArtworkOptions{100.0, true}, path);
    std::vector<int> ids = detectors.at(name)(vision::imread(path, cv::IMREAD_GRAYSCALE));
    std::sort(ids.begin(), ids.end());
    EXPECT_EQ(ids, (std::vector<int>{0, 1, 2, 3})) << name;
    std::filesystem::remove(path);
  }
}

std::string layout_error(const std::string& extra) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "rig_marker_family_layout.toml").string();
  std::ofstream(path) << "paper = \"A4\"\norigin_mm = [105.0, 148.5]\npose_marker = 0\n"
                      << extra << "\n[[markers]]\nid = 0\nside_mm = 50.0\ncentre_mm = [0.0, 0.0]\n"
                      << "[[markers]]\nid = 40\nside_mm = 50.0\ncentre_mm = [0.0, 90.0]\n";
  try {
    const Target t = Target::load(path);
    return "loaded, family " + t.family;
  } catch (const TargetError& e) {
    return e.what();
  }
}

TEST(MarkerFamily, LayoutFamilyKeyIsCheckedWithTheFileKeyAndAcceptedNames) {
  const std::string unknown = layout_error("family = \"aruco:DICT_5X5_100\"");
  EXPECT_NE(unknown.find("rig_marker_family_layout.toml"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("family"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("aruco:DICT_6X6_250"), std::string::npos) << unknown;
  // id 40 is in DICT_4X4_50 (0 .. 49) but not in tag16h5 (0 .. 29) nor rig4x4 (0 .. 34).
  EXPECT_EQ(layout_error("family = \"aruco:DICT_4X4_50\""), "loaded, family aruco:DICT_4X4_50");
  const std::string tag16 = layout_error("family = \"apriltag:tag16h5\"");
  EXPECT_NE(tag16.find("markers[1].id = 40"), std::string::npos) << tag16;
  EXPECT_NE(tag16.find("0 .. 29"), std::string::npos) << tag16;
  const std::string rig = layout_error("");
  EXPECT_NE(rig.find("0 .. 34"), std::string::npos) << rig;
}

}  // namespace
}  // namespace vision
