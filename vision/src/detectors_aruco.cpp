// cv::aruco::detectMarkers in the detector registry (vision/detectors.hpp).
// OpenCV 4.6's aruco module; Garrido-Jurado et al. 2014,
// DOI 10.1016/j.patcog.2014.01.005; CORNER_REFINE_APRILTAG after Wang &
// Olson 2016 (AprilTag 2).
#include <opencv2/aruco.hpp>

#include "detectors_internal.hpp"
#include "vision/codebook.hpp"
#include "vision/marker_family.hpp"

namespace vision::detectors_internal {
namespace {

// rig's codebook as an ArUco dictionary: each id's code cells (1 = white,
// row-major from the printed top-left, as MarkerFamily::cell_is_white), with
// the correction rig's own decoder applies.
cv::Ptr<cv::aruco::Dictionary> rig_dictionary() {
  const MarkerFamily& family = MarkerFamily::named(MarkerFamily::kDefaultName);
  const int n = family.code_cells();
  cv::Mat bytes;
  for (int id = 0; id < family.size(); ++id) {
    cv::Mat bits(n, n, CV_8UC1);
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c)
        bits.at<uint8_t>(r, c) = family.cell_is_white(id, r + 1, c + 1) ? 1 : 0;
    bytes.push_back(cv::aruco::Dictionary::getByteListFromBits(bits));
  }
  return cv::makePtr<cv::aruco::Dictionary>(bytes, n, Codebook().max_correction_bits());
}

cv::Ptr<cv::aruco::Dictionary> dictionary_of(const std::string& family) {
  using cv::aruco::getPredefinedDictionary;
  if (family == "aruco:DICT_4X4_50") return getPredefinedDictionary(cv::aruco::DICT_4X4_50);
  if (family == "aruco:DICT_6X6_250") return getPredefinedDictionary(cv::aruco::DICT_6X6_250);
  if (family == "aruco:DICT_APRILTAG_36h11" || family == "apriltag:tag36h11")
    return getPredefinedDictionary(cv::aruco::DICT_APRILTAG_36h11);
  if (family == "apriltag:tag16h5") return getPredefinedDictionary(cv::aruco::DICT_APRILTAG_16h5);
  return rig_dictionary();  // rig4x4, the only other family detector_reads allows
}

int refinement_method(const std::string& refinement) {
  if (refinement == "subpix") return cv::aruco::CORNER_REFINE_SUBPIX;
  if (refinement == "contour") return cv::aruco::CORNER_REFINE_CONTOUR;
  if (refinement == "apriltag") return cv::aruco::CORNER_REFINE_APRILTAG;
  return cv::aruco::CORNER_REFINE_NONE;
}

class ArucoDetector : public FiducialDetector {
 public:
  ArucoDetector(const std::string& refinement, const std::string& family)
      : name_("aruco:" + refinement),
        family_(family),
        dictionary_(dictionary_of(family)),
        parameters_(cv::aruco::DetectorParameters::create()),
        // OpenCV's DICT_APRILTAG_* hold libapriltag's codes turned by 180
        // degrees, under the same ids: its top-left is the printed AprilTag's
        // bottom-right (checked cell by cell in tests/vision/detectors_test.cpp).
        first_corner_(family.rfind("apriltag:", 0) == 0 ? 2 : 0),
        // CORNER_REFINE_APRILTAG keeps the quads of OpenCV's port of
        // AprilTag 2's apriltag_quad_thresh, whose pixel centres are at +0.5
        // (as libapriltag's); the other refinements use OpenCV's convention.
        offset_px_(refinement == "apriltag" ? -0.5 : 0.0) {
    parameters_->cornerRefinementMethod = refinement_method(refinement);
  }
  const std::string& name() const override { return name_; }
  const std::string& family() const override { return family_; }

  std::vector<Detection> detect(const cv::Mat& image) const override {
    const cv::Mat gray = to_gray8(image);
    std::vector<Detection> detections;
    if (gray.empty()) return detections;
    std::vector<std::vector<cv::Point2f>> corners;
    std::vector<int> ids;
    cv::aruco::detectMarkers(gray, dictionary_, corners, ids, parameters_);
    for (size_t k = 0; k < ids.size(); ++k) {
      Detection d;
      d.id = ids[k];
      // cv::aruco's order is its code's top-left, top-right, bottom-right,
      // bottom-left: A, B, C, D of the printed marker from first_corner_ on.
      for (int j = 0; j < 4; ++j) {
        const cv::Point2f& p = corners[k][static_cast<size_t>((j + first_corner_) % 4)];
        d.corners_px[static_cast<size_t>(j)] = Eigen::Vector2d(p.x + offset_px_, p.y + offset_px_);
      }
      d.rotation = quarter_turns_of(d.corners_px);
      detections.push_back(d);
    }
    sort_detections(detections);
    return detections;
  }

 private:
  std::string name_;
  std::string family_;
  cv::Ptr<cv::aruco::Dictionary> dictionary_;
  cv::Ptr<cv::aruco::DetectorParameters> parameters_;
  int first_corner_;  // the corner of cv::aruco's that is the printed A
  double offset_px_;  // to OpenCV's pixel convention
};

}  // namespace

std::unique_ptr<FiducialDetector> make_aruco_detector(const std::string& refinement,
                                                      const std::string& family) {
  return std::make_unique<ArucoDetector>(refinement, family);
}

}  // namespace vision::detectors_internal
