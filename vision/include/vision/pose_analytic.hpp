// analytic: the closed-form pose of a square (Didier 2005, as given in Maidi et
// al. 2010, §2.1, eqs. 3-5).
//
// For the corners A, B, C, D of a square in order around it, AB = DC. With the
// undistorted normalized image points a, b, c, d (homogeneous, z = 1) and the
// corner depths Z, Z_A a - Z_B b + Z_C c - Z_D d = 0; fixing Z_A = 1 gives the
// 3x3 linear system of eq. 3, solved in closed form by eq. 4 (Cramer's rule).
// The known side fixes the scale; the translation is the centre of the four
// corners; the rotation comes from the diagonals: the sum and difference of
// AC and DB are along the square's x and y axes (eq. 5 as printed has AB + DB
// for r1, a typesetting slip: only AC + DB is parallel to AB for a square), made
// orthonormal (nearest rotation), r3 = r1 x r2.
//
// Applies only to four points forming a square (Correspondences::square_side_m);
// anything else is reported as not applicable. No iteration, no initial guess.
#pragma once

#include "vision/pose_solver.hpp"

namespace vision {

class AnalyticSolver : public PoseSolver {
 public:
  std::string name() const override { return "analytic"; }

 protected:
  Estimate solve_pose(const Correspondences& c, const SolverHint& hint) const override;
};

// The closed-form square pose from the first four correspondences, which must
// be a square (c.square_side_m set). Used by the hybrids as their start.
// Returns false when the linear system of eq. 3 is singular or a depth is not
// positive (the square seen edge-on, or a corrupt quadrilateral).
bool analytic_square_pose(const Correspondences& c, Pose* T_cam_target, std::string* why);

}  // namespace vision
