// lm: Levenberg-Marquardt on the reprojection error in pixels, through the full
// camera model including distortion: the maximum-likelihood pose under
// isotropic Gaussian corner noise (Hartley & Zisserman 2004, §A6.2; More 1978
// for the damping schedule). The reference optimum the others are measured by.
//
// Parameters: a rotation increment (axis-angle, left-multiplied) and a
// translation increment, with the analytic Jacobian of
// vision/pose_jacobian.hpp. Started from the best (lowest reprojection error)
// of the solvers that can start it: IPPE's better solution (both when they
// are nearly ambiguous), the hint, and hybrid_oi's when IPPE fails.
#pragma once

#include "vision/pose_solver.hpp"

namespace vision {

struct LmOptions {
  // Iteration cap; from a good start LM reaches the tolerance in 3-10 steps.
  int max_iterations = 100;
  // Stop when the relative decrease of the squared error, or the step size
  // (radians / metres), falls below these. Smaller: closer to the optimum.
  double relative_tolerance = 1e-10;
  double step_tolerance = 1e-9;
};

class LmSolver : public PoseSolver {
 public:
  explicit LmSolver(LmOptions options = {}) : options_(options) {}
  std::string name() const override { return "lm"; }

 protected:
  Estimate solve_pose(const Correspondences& c, const SolverHint& hint) const override;

 private:
  LmOptions options_;
};

// LM refinement from a given start.
Estimate refine_lm(const Correspondences& c, const Pose& start, const LmOptions& options);

}  // namespace vision
