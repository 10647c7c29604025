// vision::FrameMeasurer: what one frame yields (Maidi et al. 2010, §3): the
// fiducials in it, and every pose solver's estimate of T_cam_target from the
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
#include "vision/pose_solver.hpp"
#include "vision/target.hpp"

namespace vision {

struct ScopeEstimate {
  std::string scope;  // "0" (the pose marker's id) or "target"
  vision::Estimate estimate;
  std::optional<double> generalization_error_px;  // pose-marker scope only
};

struct FrameMeasurement {
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

class FrameMeasurer {
 public:
  // Every solver of vision's registry (vision::make_all_solvers()).
  FrameMeasurer(vision::Camera camera, vision::Target target,
                vision::DetectorParameters parameters = {});

  // Detects and solves. Precondition: the image is what `camera` sees (its
  // size is checked by the caller before a sweep starts). Throws
  // std::invalid_argument for an image type the detector cannot read.
  FrameMeasurement measure(const cv::Mat& image) const;

  const vision::Camera& camera() const { return camera_; }
  const vision::Target& target() const { return target_; }
  const std::vector<std::string>& solver_names() const { return names_; }

 private:
  vision::Camera camera_;
  vision::Target target_;
  vision::Detector detector_;
  std::vector<std::unique_ptr<vision::PoseSolver>> solvers_;
  std::vector<std::string> names_;
};

}  // namespace vision
