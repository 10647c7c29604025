// vision::FrameMeasurer: what one frame yields (Maidi et al. 2010, §3): for
// each detector of the registry it is given (vision/detectors.hpp), the
// fiducials it finds, and on its corners every pose solver's estimate of T_cam_target from the
// pose marker alone and from the whole target, with the reconstruction
// (reprojection) error and, for the pose marker, the generalization error.
//
// Scopes. "<pose marker id>" (e.g. "0"): the pose marker's four corners A, B,
// C, D. "target": every detected marker of the layout, the pose marker's
// corners first when it is seen. A marker id seen twice in one frame is
// ambiguous and used in neither scope.
//
// Generalization error (paper §3.2): the pose from the pose marker alone,
// used to project the corners of the OTHER detected markers of the layout;
// the RMS distance, in distorted pixels, between those projections and the
// detected corners. Absent when no other marker is detected or the solver
// gave no usable pose.
#pragma once

#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "vision/camera.hpp"
#include "vision/detector.hpp"
#include "vision/detectors.hpp"
#include "vision/pose_solver.hpp"
#include "vision/target.hpp"

namespace vision {

struct ScopeEstimate {
  std::string scope;  // "0" (the pose marker's id) or "target"
  vision::Estimate estimate;
  std::optional<double> generalization_error_px;  // pose-marker scope only
};

// What one detector's corners yield on one frame.
struct DetectorMeasurement {
  std::string detector;                       // registry name (vision/detectors.hpp), e.g. "rig"
  std::vector<vision::Detection> detections;  // as the detector returned them
  std::vector<ScopeEstimate> estimates;       // per scope, every solver in registry order
  // Why a scope has no estimates (correspondences no solver can take); empty otherwise.
  struct ScopeError {
    std::string scope;    // as ScopeEstimate::scope
    std::string message;  // vision::InputError's, naming the point and what was expected
  };
  std::vector<ScopeError> scope_errors;
  double detect_s = 0;                    // detector wall time, seconds
  std::map<std::string, double> solve_s;  // per solver, both scopes, seconds
};

struct FrameMeasurement {
  // One entry per detector of the measurer, in its detector_names() order;
  // never empty.
  std::vector<DetectorMeasurement> detectors;
  // The primary detector's: detectors.front() (rig's detector when it reads
  // the target's family and is measured, otherwise the first detector).
  const DetectorMeasurement& primary() const { return detectors.front(); }
};

class FrameMeasurer {
 public:
  // Every solver of vision's registry (vision::make_all_solvers()) on the
  // corners of each detector in `detectors` (registry names; run in
  // vision::detector_names() order whatever the order given, each once).
  // Empty: the first detector of the registry that reads the target's family
  // (rig's for rig4x4). `parameters` are rig's detector's thresholds. Throws
  // vision::DetectorRegistryError naming the detector and the family when a
  // detector is unknown or cannot decode the target's family, or when no
  // detector decodes it.
  FrameMeasurer(vision::Camera camera, vision::Target target,
                vision::DetectorParameters parameters = {},
                std::vector<std::string> detectors = {});

  // Detects with every detector and solves on each one's corners. Const and
  // free of shared mutable state: safe to call from several threads at once.
  // Precondition: the image is what `camera` sees (its size is checked by
  // the caller before a sweep starts). Throws std::invalid_argument for an
  // image type the detectors cannot read.
  FrameMeasurement measure(const cv::Mat& image) const;

  const vision::Camera& camera() const { return camera_; }
  const vision::Target& target() const { return target_; }
  const std::vector<std::string>& solver_names() const { return names_; }
  // The detectors measured, in FrameMeasurement::detectors order.
  const std::vector<std::string>& detector_names() const { return detector_names_; }

 private:
  vision::Camera camera_;
  vision::Target target_;
  std::vector<std::unique_ptr<vision::FiducialDetector>> detectors_;
  std::vector<std::string> detector_names_;
  std::vector<std::unique_ptr<vision::PoseSolver>> solvers_;
  std::vector<std::string> names_;
};

}  // namespace vision
