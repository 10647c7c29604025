// vision::PoseSolver: the interface every pose solver implements, and the
// Estimate (result and summary) each returns.
//
// Ceres-style: a solver returns its answer together with how it got there
// (iterations, whether it converged, why it stopped, how long it took). A
// solver that does not converge, or that does not apply to the input, says so
// in the Estimate; it does not throw. Exceptions are for bad input, which
// make_correspondences rejects before any solver runs.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>

#include "vision/correspondences.hpp"
#include "vision/pose.hpp"

namespace vision {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

enum class Termination {
  kConverged,         // the solver's own stopping rule was met
  kClosedForm,        // a direct solution; nothing to iterate
  kMaxIterations,     // the iteration budget ran out before convergence
  kNotApplicable,     // the input is not of the kind the solver handles
  kDegenerate,        // the geometry gives no unique pose (e.g. a singular system)
  kBehindCamera,      // the result puts an object point on or behind the camera
  kLocalMinimum,      // stopped, but the residual is inconsistent with the noise
  kNumericalFailure,  // NaN or infinity appeared
};
const char* to_string(Termination t);

struct Estimate {
  std::string solver;
  Pose T_cam_target;                 // object (target frame) to camera, metres
  double distance_m = 0;             // |t|: camera centre to target-frame origin, metres
  double reprojection_error_px = 0;  // RMS over all points, full camera model, pixels
  int iterations = 0;                // 0 for closed-form solvers
  bool converged = false;            // true only for a finite, usable pose
  Termination termination = Termination::kNumericalFailure;
  std::string message;  // detail on termination, for people
  double time_us = 0;   // wall time of solve(), microseconds
  // IPPE-family only: reprojection error of the better of the two planar
  // solutions over that of the worse, in [0, 1]. Near 1 the two poses explain
  // the image equally well (planar ambiguity, Collins & Bartoli 2014 §5).
  std::optional<double> ambiguity_ratio;
  // Posterior covariance of (psi, theta, phi, tx, ty, tz) where the solver
  // tracks one (the EKF); radians and metres squared.
  std::optional<Matrix6d> covariance;

  bool applicable() const { return termination != Termination::kNotApplicable; }
};

// What a solver may start from. Absent fields mean "use your own initialisation".
struct SolverHint {
  // A pose to start from (e.g. the previous frame's estimate at the same bench
  // position). Iterative solvers use it; closed-form solvers ignore it.
  std::optional<Pose> T_cam_target;
  // Covariance carried with T_cam_target (the EKF's state across frames).
  std::optional<Matrix6d> covariance;
};

class PoseSolver {
 public:
  virtual ~PoseSolver() = default;
  virtual std::string name() const = 0;

  // Solves for T_cam_target. Fills, uniformly for every solver: solver name,
  // distance, reprojection error, time; and turns a non-finite pose or one
  // that puts a point behind the camera into converged = false with the
  // matching termination, so that no caller ever sees an unflagged bad pose.
  Estimate solve(const Correspondences& c, const SolverHint& hint = {}) const;

 protected:
  // The algorithm. Implementations set T_cam_target, iterations, converged,
  // termination and message (and ambiguity_ratio / covariance where defined).
  virtual Estimate solve_pose(const Correspondences& c, const SolverHint& hint) const = 0;
};

// An Estimate with no pose: converged = false, the given termination (not
// kConverged or kClosedForm) and a message for people.
Estimate unsolved(Termination why, const std::string& message);

}  // namespace vision
