// opencv_*: OpenCV's cv::solvePnP as external references, in the same registry.
//   opencv_ippe_square  SOLVEPNP_IPPE_SQUARE (Collins & Bartoli 2014; 4 points of a
//                       square centred on the origin: applied only to those)
//   opencv_iterative    SOLVEPNP_ITERATIVE (homography start, then LM)
//   opencv_sqpnp        SOLVEPNP_SQPNP (Terzakis & Lourakis 2020)
// They are given the pixels undistorted once by our camera model (and no
// distortion coefficients), like every other solver: cv::undistortPoints' fixed
// five iterations would otherwise add up to 1e-4 px of error near the image
// corners. converged is solvePnP's return value: OpenCV reports no more.
#pragma once

#include "vision/pose_solver.hpp"

namespace vision {

class OpenCvSolver : public PoseSolver {
 public:
  enum class Method { kIppeSquare, kIterative, kSqpnp };
  explicit OpenCvSolver(Method method) : method_(method) {}
  std::string name() const override;

 protected:
  Estimate solve_pose(const Correspondences& c, const SolverHint& hint) const override;

 private:
  Method method_;
};

}  // namespace vision
