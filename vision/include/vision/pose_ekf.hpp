// ekf: the paper's extended Kalman filter pose estimator (Maidi et al. 2010,
// §2.3, eqs. 12-29), after Maidi et al. 2005.
//
// State x = (psi, theta, phi, tx, ty, tz): Z-Y-X Euler angles (radians) of
// R_cam_target = Rz(psi) Ry(theta) Rx(phi) and t_cam_target (metres). Process
// model A = I (eqs. 18-20). Measurements: the projected corners (eq. 14),
// u_i = (M1 P_i + M14) / (M3 P_i + M34), v_i likewise (eqs. 15-17), in
// undistorted pixels (distortion is removed once by the camera model). H is the
// analytic Jacobian of h (eq. 29).
//
// On one frame it runs as an iterated EKF: the measurement update (eqs. 25-28)
// is relinearised about the current state until the state stops changing, which
// makes it a Gauss-Newton solve regularised by the prior. Across several frames
// of one bench position the state and covariance are carried (SolverHint) with
// the time update P += Q (eq. 19).
//
// hybrid_ekf (§2.3.3, Fig. 4) takes its prior mean from the analytic square pose.
#pragma once

#include <optional>

#include "vision/pose_solver.hpp"

namespace vision {

// The instruction sets the filter's inner loops are built for: the baseline
// the program is built for, and AVX2 with FMA (four corners in one
// register, fused multiply-adds), chosen when the CPU runs it. Both give the
// same iterates to rounding (tests/vision/pose_ekf_reference_test.cpp).
enum class EkfInstructionSet { kBaseline, kAvx2Fma };

// Whether this CPU runs `set`.
bool cpu_runs(EkfInstructionSet set);

struct EkfOptions {
  // Standard deviation of a corner measurement, pixels (R = sigma^2 I). Smaller
  // trusts the image more against the prior; it also sets the consistency
  // gate below. Match it to the detector's corner noise.
  double measurement_sigma_px = 0.5;
  // Prior standard deviations of the fixed nominal prior (ekf without a hint):
  // angles (radians) and translation (metres). Wider: a weaker pull toward the
  // nominal pose, and a larger basin of wrong minima.
  double prior_sigma_angle_rad = 0.5;
  double prior_sigma_translation_m = 0.5;
  // Nominal prior mean: the target frontal (R = I, the target's z along the
  // optical axis), centred on the optical axis at this depth, metres.
  double prior_depth_m = 0.5;
  // Process noise per frame (eq. 19, Q diagonal) when state is carried across
  // frames of one bench position: radians^2 and metres^2. The bench is still,
  // so small values; larger lets the state follow residual vibration.
  double process_sigma_angle_rad = 1e-4;
  double process_sigma_translation_m = 1e-5;
  // Iterated-update cap and stopping rule: stop when the state step is below
  // this (radians / metres). 1e-7 (0.1 µrad, 0.1 µm) is far below any pose
  // noise of the rig; each further decade costs ~0.6 iterations (~0.3 µs)
  // for digits no measurement has.
  int max_iterations = 100;
  double state_tolerance = 1e-7;
  // Consistency gate: a converged state whose RMS residual exceeds this many
  // measurement sigmas is reported converged = false (kLocalMinimum): a wrong
  // local minimum, or corners that no one pose fits (a corner mislocated by
  // its detector, which every solver then explains as badly).
  double gate_sigmas = 5.0;
  // The build of the inner loops to run; unset, or one the CPU does not run:
  // the fastest it runs. Tests set it to check each build.
  std::optional<EkfInstructionSet> instruction_set;
};

class EkfSolver : public PoseSolver {
 public:
  explicit EkfSolver(EkfOptions options = {}) : options_(options) {}
  std::string name() const override { return "ekf"; }

 protected:
  // Prior: the hint's pose and covariance when given (carried state; the time
  // update adds Q), otherwise the fixed nominal prior of EkfOptions.
  Estimate solve_pose(const Correspondences& c, const SolverHint& hint) const override;

 private:
  EkfOptions options_;
};

class HybridEkfSolver : public PoseSolver {
 public:
  explicit HybridEkfSolver(EkfOptions options = {}) : options_(options) {}
  std::string name() const override { return "hybrid_ekf"; }

 protected:
  // Prior mean from analytic_square_pose on the first four points (or the
  // hint's carried state when given). Not applicable when neither exists.
  Estimate solve_pose(const Correspondences& c, const SolverHint& hint) const override;

 private:
  EkfOptions options_;
};

// The iterated EKF from a prior mean and covariance (state order as above).
Estimate iterated_ekf(const Correspondences& c, const Pose& prior, const Matrix6d& prior_covariance,
                      const EkfOptions& options);

}  // namespace vision
