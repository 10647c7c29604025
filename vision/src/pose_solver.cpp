#include "vision/pose_solver.hpp"

#include <chrono>
#include <limits>

namespace vision {

const char* to_string(Termination t) {
  switch (t) {
    case Termination::kConverged:
      return "converged";
    case Termination::kClosedForm:
      return "closed_form";
    case Termination::kMaxIterations:
      return "max_iterations";
    case Termination::kNotApplicable:
      return "not_applicable";
    case Termination::kDegenerate:
      return "degenerate";
    case Termination::kBehindCamera:
      return "behind_camera";
    case Termination::kLocalMinimum:
      return "local_minimum";
    case Termination::kNumericalFailure:
      return "numerical_failure";
  }
  return "unknown";
}

Estimate unsolved(Termination why, const std::string& message) {
  Estimate e;
  e.termination = why;
  e.converged = false;
  e.message = message;
  return e;
}

Estimate PoseSolver::solve(const Correspondences& c, const SolverHint& hint) const {
  const auto start = std::chrono::steady_clock::now();
  Estimate e = solve_pose(c, hint);
  const auto stop = std::chrono::steady_clock::now();
  e.time_us = std::chrono::duration<double, std::micro>(stop - start).count();
  e.solver = name();
  if (!e.applicable()) return e;

  const Pose& T = e.T_cam_target;
  const bool finite = T.R.allFinite() && T.t.allFinite();
  // A rotation that drifted from orthonormal by more than 1e-6 is a solver
  // bug or a numerical breakdown, not a pose.
  const bool orthonormal = finite &&
                           (T.R.transpose() * T.R - Eigen::Matrix3d::Identity()).norm() < 1e-6 &&
                           T.R.determinant() > 0;
  if (!finite || !orthonormal) {
    e.converged = false;
    e.termination = Termination::kNumericalFailure;
    if (e.message.empty()) e.message = finite ? "rotation is not orthonormal" : "non-finite pose";
    e.distance_m = std::numeric_limits<double>::quiet_NaN();
    e.reprojection_error_px = std::numeric_limits<double>::infinity();
    return e;
  }
  e.distance_m = T.distance_m();
  if (!in_front_of_camera(c, T)) {
    e.converged = false;
    e.termination = Termination::kBehindCamera;
    e.message = "the pose puts an object point on or behind the camera";
    e.reprojection_error_px = std::numeric_limits<double>::infinity();
    return e;
  }
  e.reprojection_error_px = reprojection_rms_px(c, T);
  return e;
}

}  // namespace vision
