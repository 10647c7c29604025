// The detector registry (vision/detectors.hpp) and rig's own detector in it.
#include "vision/detectors.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "detectors_internal.hpp"
#include "vision/codebook.hpp"
#include "vision/marker_family.hpp"

namespace vision {
namespace {

// Which families each detector decodes (see the header's table).
const std::map<std::string, std::vector<std::string>>& families_read() {
  static const std::vector<std::string> kAruco = {"rig4x4",
                                                  "aruco:DICT_4X4_50",
                                                  "aruco:DICT_6X6_250",
                                                  "aruco:DICT_APRILTAG_36h11",
                                                  "apriltag:tag36h11",
                                                  "apriltag:tag16h5"};
  static const std::vector<std::string> kAprilTag = {"rig4x4", "aruco:DICT_APRILTAG_36h11",
                                                     "apriltag:tag36h11", "apriltag:tag16h5"};
  static const std::map<std::string, std::vector<std::string>> kRead = {
      {"rig", {"rig4x4"}},       {"aruco:none", kAruco},     {"aruco:subpix", kAruco},
      {"aruco:contour", kAruco}, {"aruco:apriltag", kAruco}, {"apriltag:d1", kAprilTag},
      {"apriltag:d2", kAprilTag}};
  return kRead;
}

// rig's detector (vision::Detector) behind the registry's interface.
class RigDetector : public FiducialDetector {
 public:
  RigDetector(const Camera& camera, const DetectorParameters& parameters)
      : detector_(camera, Codebook(), parameters) {}
  const std::string& name() const override { return name_; }
  const std::string& family() const override { return family_; }
  std::vector<Detection> detect(const cv::Mat& image) const override {
    return detector_.detect(image);
  }

 private:
  Detector detector_;
  std::string name_ = "rig";
  std::string family_ = MarkerFamily::kDefaultName;
};

std::string quoted_list(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& n : names)
    text += (text.empty() ? "\"" : ", \"") + n + "\"";
  return text;
}

}  // namespace

const std::vector<std::string>& detector_names() {
  static const std::vector<std::string> kNames = {"rig",           "aruco:none",     "aruco:subpix",
                                                  "aruco:contour", "aruco:apriltag", "apriltag:d1",
                                                  "apriltag:d2"};
  return kNames;
}

std::string detector_names_text() {
  return quoted_list(detector_names());
}

bool detector_reads(const std::string& detector, const std::string& family) {
  const auto it = families_read().find(detector);
  if (it == families_read().end()) return false;
  return std::find(it->second.begin(), it->second.end(), family) != it->second.end();
}

std::vector<std::string> detectors_for_family(const std::string& family) {
  std::vector<std::string> out;
  for (const std::string& d : detector_names())
    if (detector_reads(d, family)) out.push_back(d);
  return out;
}

std::unique_ptr<FiducialDetector> make_detector(const std::string& name, const Camera& camera,
                                                const std::string& family,
                                                const DetectorParameters& rig_parameters) {
  if (families_read().count(name) == 0) {
    throw DetectorRegistryError("detector \"" + name + "\": expected one of " +
                                detector_names_text());
  }
  if (!detector_reads(name, family)) {
    const std::vector<std::string> able = detectors_for_family(family);
    throw DetectorRegistryError(
        "detector \"" + name + "\" cannot decode marker family \"" + family + "\"; " +
        (able.empty() ? std::string("no detector decodes it")
                      : "expected a detector that does: " + quoted_list(able)));
  }
  if (name == "rig") return std::make_unique<RigDetector>(camera, rig_parameters);
  if (name.rfind("aruco:", 0) == 0)
    return detectors_internal::make_aruco_detector(name.substr(6), family);
  return detectors_internal::make_apriltag_detector(name == "apriltag:d1" ? 1 : 2, family);
}

int quarter_turns_of(const std::array<Eigen::Vector2d, 4>& corners_px) {
  const Eigen::Vector2d ab = corners_px[1] - corners_px[0];
  const double quarter = std::atan2(ab.y(), ab.x()) / (M_PI / 2);  // y down: +1 is clockwise
  const int turns = static_cast<int>(std::lround(quarter));
  return ((turns % 4) + 4) % 4;
}

namespace detectors_internal {

void sort_detections(std::vector<Detection>& detections) {
  std::sort(detections.begin(), detections.end(), [](const Detection& a, const Detection& b) {
    if (a.id != b.id) return a.id < b.id;
    if (a.corners_px[0].y() != b.corners_px[0].y())
      return a.corners_px[0].y() < b.corners_px[0].y();
    return a.corners_px[0].x() < b.corners_px[0].x();
  });
}

}  // namespace detectors_internal
}  // namespace vision
