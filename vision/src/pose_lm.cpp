#include "vision/pose_lm.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>

#include "vision/pose_ippe.hpp"
#include "vision/pose_jacobian.hpp"
#include "vision/pose_oi.hpp"

namespace vision {
namespace {

// IPPE solutions whose reprojection errors are within this ratio are both
// refined. Lower: faster, with a risk of refining only the wrong one of a
// nearly ambiguous pair; 0.3 keeps every pair that 0.5 px noise can swap at
// the paper's range (measured: the wrong IPPE solution of a 5 cm marker is
// then at least ~3x worse than the right one when it is not ambiguous).
constexpr double kAmbiguousRatio = 0.3;

using Vector6d = Eigen::Matrix<double, 6, 1>;

// exp([w]x): the rotation by |w| radians about w (identity for w = 0).
Eigen::Matrix3d rotation_from_axis_angle(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

// Squared reprojection error (px^2) and, when wanted, the Gauss-Newton system
// J^T J and J^T r for the increments (w, v) of vision/pose_jacobian.hpp.
double reprojection_system(const Correspondences& c, const Pose& T, Matrix6d* JtJ, Vector6d* Jtr) {
  const Camera& cam = *c.camera;
  double sum = 0;
  if (JtJ) {
    JtJ->setZero();
    Jtr->setZero();
  }
  Eigen::Vector2d px;
  ProjectionJacobian J;
  for (size_t i = 0; i < c.size(); ++i) {
    if (!project_with_jacobian(cam, T, c.object_points[i], &px, JtJ ? &J : nullptr))
      return std::numeric_limits<double>::infinity();
    const Eigen::Vector2d r = px - c.image_points_px[i];
    sum += r.squaredNorm();
    if (!JtJ) continue;
    *JtJ += J.transpose() * J;
    *Jtr += J.transpose() * r;
  }
  return sum;
}

}  // namespace

Estimate refine_lm(const Correspondences& c, const Pose& start, const LmOptions& options) {
  Estimate e;
  Pose T = start;
  Matrix6d JtJ;
  Vector6d Jtr;
  double cost = reprojection_system(c, T, &JtJ, &Jtr);
  if (!std::isfinite(cost))
    return unsolved(Termination::kBehindCamera, "the starting pose puts a point behind the camera");
  // Marquardt's scaling: damping proportional to the diagonal of J^T J, with
  // the factor-of-ten schedule (More 1978 gives the trust-region view).
  double lambda = 1e-3;
  e.termination = Termination::kMaxIterations;
  for (int it = 1; it <= options.max_iterations; ++it) {
    e.iterations = it;
    Matrix6d A = JtJ;
    A.diagonal() *= 1.0 + lambda;
    const Vector6d step = -A.ldlt().solve(Jtr);
    if (!step.allFinite()) {
      e.termination = Termination::kNumericalFailure;
      e.message = "the damped normal equations are singular";
      break;
    }
    const Pose next{rotation_from_axis_angle(step.head<3>()) * T.R, T.t + step.tail<3>()};
    Matrix6d JtJ_next;
    Vector6d Jtr_next;
    const double next_cost = reprojection_system(c, next, &JtJ_next, &Jtr_next);
    if (next_cost < cost) {
      const bool small_decrease = cost - next_cost <= options.relative_tolerance * cost;
      T = next;
      cost = next_cost;
      JtJ = JtJ_next;
      Jtr = Jtr_next;
      lambda = std::max(lambda / 10, 1e-12);
      if (small_decrease || step.norm() <= options.step_tolerance) {
        e.termination = Termination::kConverged;
        break;
      }
    } else {
      // No decrease: at the optimum up to rounding when the step is tiny,
      // otherwise damp harder and try again.
      if (step.norm() <= options.step_tolerance || cost == 0) {
        e.termination = Termination::kConverged;
        break;
      }
      lambda *= 10;
      if (lambda > 1e12) {
        e.termination = Termination::kConverged;
        e.message = "no further decrease possible (damping saturated)";
        break;
      }
    }
  }
  e.T_cam_target = T;
  e.converged = e.termination == Termination::kConverged;
  if (e.termination == Termination::kMaxIterations)
    e.message = "no convergence in " + std::to_string(options.max_iterations) + " iterations";
  return e;
}

Estimate LmSolver::solve_pose(const Correspondences& c, const SolverHint& hint) const {
  // Candidate starts: IPPE's better solution, and its other one too when the
  // pair is ambiguous (noise can swap which is better, and LM only descends),
  // the hint, and hybrid_oi's pose when IPPE fails. Each is refined; the
  // lowest reprojection error wins.
  std::vector<Pose> starts;
  std::array<Pose, 2> ippe;
  std::array<double, 2> ippe_rms;
  if (ippe_solutions(c, &ippe, &ippe_rms)) {
    starts.push_back(ippe[0]);
    if (ippe_rms[0] > kAmbiguousRatio * ippe_rms[1]) starts.push_back(ippe[1]);
  }
  if (hint.T_cam_target) starts.push_back(*hint.T_cam_target);
  if (starts.empty()) {
    const Estimate oi = HybridOiSolver().solve(c);
    if (oi.converged) starts.push_back(oi.T_cam_target);
  }
  if (starts.empty())
    return unsolved(Termination::kDegenerate, "no starting pose: IPPE and hybrid_oi both failed");
  Estimate best;
  double best_rms = std::numeric_limits<double>::infinity();
  int iterations = 0;
  for (const auto& start : starts) {
    Estimate e = refine_lm(c, start, options_);
    iterations += e.iterations;
    const double rms = e.applicable() ? reprojection_rms_px(c, e.T_cam_target)
                                      : std::numeric_limits<double>::infinity();
    if (rms < best_rms || best.termination == Termination::kNumericalFailure) {
      best = e;
      best_rms = rms;
    }
  }
  best.iterations = iterations;
  return best;
}

}  // namespace vision
