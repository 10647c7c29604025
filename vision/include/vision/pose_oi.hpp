// oi: orthogonal iteration (Lu, Hager, Mjolsness, "Fast and globally convergent
// pose estimation from video images", IEEE PAMI 22(6), 2000), as used in Maidi
// et al. 2010, §2.2, eqs. 6-11.
//
// Minimises the object-space collinearity error (eq. 11)
//   E(R, t) = sum_i || (I - V_i) (R P_i + t) ||^2,  V_i = v_i v_i^T / (v_i^T v_i)  (eq. 10)
// over rotations R and translations t: for a fixed R the optimal t is linear
// (Lu et al. eq. 20), and for a fixed set of projected points the optimal R is
// an absolute-orientation problem solved by SVD (Lu et al. §4.3). Each step
// does not increase E. The steps are extrapolated with SQUAREM (Varadhan &
// Roland 2008), which keeps OI's fixed points and only accepts a lower E.
// Where OI still crawls at its cap (near frontal, where the two planar minima
// merge and its linear rate tends to 1), Newton's method on the same E
// finishes the descent; it too only accepts a lower E, so the minimum is OI's.
//
// hybrid_oi (Maidi et al. §2.2, Fig. 3) starts OI from the analytic square pose.
#pragma once

#include "vision/pose_solver.hpp"

namespace vision {

struct OiOptions {
  // Iteration cap. OI converges linearly; from a good start 10-40 steps reach
  // the tolerance, from weak perspective up to a few hundred near the planar
  // ambiguity. At the cap up to 20 Newton steps on E finish the descent (see
  // above). Higher: slower worst case, never less accurate.
  int max_iterations = 500;
  // Stop when the relative decrease of E in one step falls below this.
  // Smaller: closer to the exact minimum, more iterations.
  double relative_tolerance = 1e-12;
  // SQUAREM extrapolation of the OI steps (see pose_oi.cpp): same minimum,
  // typically several times fewer steps. Off: the plain iteration of Lu et al.
  bool accelerate = true;
};

class OiSolver : public PoseSolver {
 public:
  explicit OiSolver(OiOptions options = {}) : options_(options) {}
  std::string name() const override { return "oi"; }

 protected:
  // Own initialisation (Lu et al. §4.4): weak perspective. For planar points it
  // has a two-fold ambiguity; OI is run from both rotations and the one with
  // the lower E is returned.
  Estimate solve_pose(const Correspondences& c, const SolverHint& hint) const override;

 private:
  OiOptions options_;
};

class HybridOiSolver : public PoseSolver {
 public:
  explicit HybridOiSolver(OiOptions options = {}) : options_(options) {}
  std::string name() const override { return "hybrid_oi"; }

 protected:
  // Starts from analytic_square_pose on the first four points (the pose
  // marker). On more points than a square it still starts from the square's
  // pose when the first four are one; otherwise it is not applicable.
  Estimate solve_pose(const Correspondences& c, const SolverHint& hint) const override;

 private:
  OiOptions options_;
};

// OI from a given starting rotation. Returns the estimate (iterations,
// termination) and the final object-space error E in *object_space_error (m^2).
Estimate orthogonal_iteration(const Correspondences& c, const Eigen::Matrix3d& R_start,
                              const OiOptions& options, double* object_space_error);

}  // namespace vision
