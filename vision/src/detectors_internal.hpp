// Internals of the detector registry (vision/detectors.hpp): the cv::aruco
// and libapriltag detectors, and what they share.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "vision/detectors.hpp"

namespace vision::detectors_internal {

// cv::aruco with `refinement` one of "none", "subpix", "contour", "apriltag".
// Precondition: detector_reads("aruco:" + refinement, family).
std::unique_ptr<FiducialDetector> make_aruco_detector(const std::string& refinement,
                                                      const std::string& family);

// libapriltag with quad_decimate `decimation` (1 or 2).
// Precondition: detector_reads("apriltag:d" + decimation, family).
std::unique_ptr<FiducialDetector> make_apriltag_detector(int decimation, const std::string& family);

// Sorts detections by id, then by corner A (row, then column).
void sort_detections(std::vector<Detection>& detections);

}  // namespace vision::detectors_internal
