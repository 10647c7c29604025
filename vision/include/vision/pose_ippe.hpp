// ippe: Infinitesimal Plane-based Pose Estimation (Collins & Bartoli, "Infinitesimal
// Plane-Based Pose Estimation", IJCV 109(3), 2014).
//
// From the homography H between the object plane and the normalized image
// (DLT on the plane points, eq. 3 there), the Jacobian J of H at a reference
// point gives the rotation in closed form up to a two-fold ambiguity (§3,
// eqs. 16-18, Algorithm 1 and eqs. 25-28); each rotation's translation
// minimises the object-space reprojection error in closed form (§4, eq. 34).
// Both solutions are kept; the one with the lower reprojection error is
// returned, and ambiguity_ratio = error(best) / error(other).
#pragma once

#include <array>

#include "vision/pose_solver.hpp"

namespace vision {

class IppeSolver : public PoseSolver {
 public:
  std::string name() const override { return "ippe"; }

 protected:
  Estimate solve_pose(const Correspondences& c, const SolverHint& hint) const override;
};

// The two IPPE solutions, best first (lower reprojection RMS in pixels).
// Returns false when the homography is degenerate.
bool ippe_solutions(const Correspondences& c, std::array<Pose, 2>* T_cam_target,
                    std::array<double, 2>* reprojection_rms_px);

}  // namespace vision
