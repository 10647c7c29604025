// The registry of fiducial detectors: every detector a sweep can run on each
// frame, each with the marker families it can decode, all returning
// vision::Detection in rig's corner order and pixel convention.
//
// Detectors (name: method, reference):
//   rig             rig's own detector (vision/detector.hpp; Maidi et al.
//                   2010, DOI 10.1007/s00138-008-0170-y, §3 and eq. 30)
//   aruco:none      cv::aruco::detectMarkers (OpenCV 4.6; Garrido-Jurado et
//   aruco:subpix      al. 2014, DOI 10.1016/j.patcog.2014.01.005) with
//   aruco:contour     cornerRefinementMethod CORNER_REFINE_NONE / SUBPIX /
//   aruco:apriltag    CONTOUR / APRILTAG (Wang & Olson 2016)
//   apriltag:d1     AprilTag 3 (libapriltag; Krogius et al. 2019,
//   apriltag:d2       DOI 10.1109/IROS40897.2019.8967787), quad_decimate 1 / 2,
//                     one thread, its other settings at their defaults
//
// Families (vision/marker_family.hpp) each reads:
//   rig          rig4x4
//   aruco:*      aruco:DICT_4X4_50, aruco:DICT_6X6_250, aruco:DICT_APRILTAG_36h11;
//                apriltag:tag36h11 and apriltag:tag16h5 through OpenCV's
//                DICT_APRILTAG_36h11 / DICT_APRILTAG_16h5; rig4x4 as a custom
//                dictionary of rig's codes (rig's 1-bit correction)
//   apriltag:*   apriltag:tag36h11, apriltag:tag16h5 (tag16h5 without
//                correction); aruco:DICT_APRILTAG_36h11 through tag36h11;
//                rig4x4 as a custom 16-bit family in tag16h5's cell order
//                (without correction: detectors_apriltag.cpp says why)
// OpenCV's DICT_APRILTAG_* are libapriltag's codes turned by 180 degrees
// under the same ids (checked cell by cell in tests/vision/detectors_test.cpp):
// read across, the corner order is turned by two so that A stays the printed
// top-left of the family the target names.
//
// Corners: A, B, C, D of the target layout (top-left, top-right, bottom-right,
// bottom-left of the printed marker), distorted pixels, OpenCV's pixel
// convention (the centre of the top-left pixel is (0, 0)), as rig's detector.
// cv::aruco uses that order and convention, except CORNER_REFINE_APRILTAG,
// whose quads (OpenCV's port of AprilTag 2's quad fitting) put pixel centres
// at +0.5 as libapriltag does: 0.5 px is subtracted. libapriltag lists the
// corners counter-clockwise from the printed bottom-left (its tag frame's
// (-1, 1), (1, 1), (1, -1), (-1, -1), y down the printed tag) and puts the
// centre of the top-left pixel at (0.5, 0.5) (the +0.5 of its quad_decimate
// rescaling, apriltag.c): its p[3], p[2], p[1], p[0] less 0.5 px are A, B, C, D.
//
// Detection::quality: rig's detector fills every field; AprilTag fills
// bits_corrected (its Hamming distance); cv::aruco measures none of them.
// Fields a detector does not measure are 0. Detection::rotation is, for
// every detector, the quarter turns clockwise of the observed marker: the
// direction of A -> B in the image rounded to a multiple of 90 degrees
// (0: to the right, 1: down, ...).
//
// Thread safety: detect() is const and may run from several threads at once
// on one detector (cv::aruco reads its dictionary and parameters only;
// libapriltag's per-call state lives in detector objects taken from a pool
// under a mutex, its decode table is built once and then only read).
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "vision/camera.hpp"
#include "vision/detector.hpp"

namespace vision {

// An unknown detector name, or a detector asked for a family it cannot
// decode. The message names the value and what was expected.
class DetectorRegistryError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// One detector of the registry, bound to one marker family and one camera.
class FiducialDetector {
 public:
  virtual ~FiducialDetector() = default;
  // The registry name, e.g. "aruco:subpix".
  virtual const std::string& name() const = 0;
  // The family it decodes, e.g. "rig4x4".
  virtual const std::string& family() const = 0;
  // The markers of family() in `image` (any type vision::to_gray8 takes),
  // ordered by id, then by position, corners as in the file comment.
  // Throws std::invalid_argument for an image type to_gray8 cannot convert.
  virtual std::vector<Detection> detect(const cv::Mat& image) const = 0;
};

// Every registered detector, in the order a sweep runs and reports them:
// rig, aruco:none, aruco:subpix, aruco:contour, aruco:apriltag, apriltag:d1,
// apriltag:d2.
const std::vector<std::string>& detector_names();

// Whether detector `detector` decodes family `family` (both registry names;
// false for an unknown name).
bool detector_reads(const std::string& detector, const std::string& family);

// The detectors that decode `family`, in detector_names() order (empty for a
// family none reads).
std::vector<std::string> detectors_for_family(const std::string& family);

// detector_names() as text for error messages: "\"rig\", \"aruco:none\", ...".
std::string detector_names_text();

// Detector `name` for markers of `family` seen through `camera` (rig's
// detector follows its distortion; the others work on the distorted image
// as it is). `rig_parameters` are rig's detector's thresholds (ignored by
// the others). Throws DetectorRegistryError naming the value: an unknown
// detector (listing the names), or a family the detector cannot decode
// (listing the detectors that can).
std::unique_ptr<FiducialDetector> make_detector(const std::string& name, const Camera& camera,
                                                const std::string& family,
                                                const DetectorParameters& rig_parameters = {});

// The quarter turns clockwise (0-3) of a marker whose corners A, B, C, D
// (distorted pixels) are `corners_px`: the angle of A -> B in the image,
// y down, rounded to a multiple of 90 degrees.
int quarter_turns_of(const std::array<Eigen::Vector2d, 4>& corners_px);

}  // namespace vision
