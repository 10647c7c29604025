// cv::calibrateCamera on the detections of a calibration problem, each
// position one view (initial guess: the nominal camera): the reference the
// calibration tests compare rig calibrate with. OpenCV cannot predict a
// position without a rig geometry; the per-view solvePnP refit of the
// held-out positions is its best case.
#pragma once

#include <array>

#include "rig/calibrate/calibration.hpp"

namespace rig_test {

struct OpenCvFit {
  vision::Camera camera = vision::Camera::paper_default();
  double rms_px = 0;               // cv::calibrateCamera's own RMS on the fit views
  double pnp_held_out_rms_px = 0;  // held-out views, pose refitted per view
};

// Views with fewer than 8 corners are left out of the fit. Runs OpenCV's
// calibration on one thread (deterministic).
OpenCvFit opencv_calibrate(const rig::calibrate::CalibrationProblem& fit,
                           const rig::calibrate::CalibrationProblem& held_out);

// fx, fy, cx, cy of `estimate` minus those of `truth`, in pixels.
inline std::array<double, 4> intrinsics_error_px(const vision::Camera& estimate,
                                                 const vision::Intrinsics& truth) {
  const vision::Intrinsics& e = estimate.intrinsics();
  return {e.fx - truth.fx, e.fy - truth.fy, e.cx - truth.cx, e.cy - truth.cy};
}

}  // namespace rig_test
