#include "vision/pose_oi.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <array>
#include <cmath>
#include <complex>
#include <limits>

#include "vision/pose_analytic.hpp"

namespace vision {
namespace {

// OI runs in the frame of the object plane, where every point is (X, Y, 0):
// R P = X r1 + Y r2 involves only the first two columns of R, so the state is
// the 3x2 matrix [r1 r2] (r3 = r1 x r2), and the nearest rotation of
// absolute orientation is the closed-form 3x2 polar factor instead of a 3x3 SVD.
using Matrix32d = Eigen::Matrix<double, 3, 2>;
using Matrix6d6 = Eigen::Matrix<double, 6, 6>;
using Vector6d6 = Eigen::Matrix<double, 6, 1>;

// vec([r1 r2]) stacks the two columns; R P = (P^T kron I3) vec for P = (X, Y).
Eigen::Matrix<double, 3, 6> kron_row(const Eigen::Vector2d& P) {
  Eigen::Matrix<double, 3, 6> K;
  K << P.x() * Eigen::Matrix3d::Identity(), P.y() * Eigen::Matrix3d::Identity();
  return K;
}

// Everything OI needs per step, precomputed once so that a step costs the
// same for 4 or 16 points (Lu et al. §4.3 note this):
//   t(R) = T vec(R)                         (Lu et al. eq. 20, linear in R)
//   vec(M(R)) = L vec(R)                    (cross-covariance of absolute orientation)
//   E(R) = vec(R)^T G vec(R)                (eq. 11 with t = t(R))
struct OiProblem {
  Eigen::Matrix<double, 3, 6> T;
  Matrix6d6 L;
  Matrix6d6 G;
};

OiProblem prepare(const Correspondences& c) {
  const size_t n = c.size();
  std::vector<Eigen::Matrix3d> V(n);
  Eigen::Matrix3d V_sum = Eigen::Matrix3d::Zero();
  Eigen::Vector2d P_mean = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d v = c.normalized[i].homogeneous();
    V[i] = v * v.transpose() / v.squaredNorm();  // eq. 10
    V_sum += V[i];
    P_mean += c.plane_points[i];
  }
  P_mean /= static_cast<double>(n);
  const Eigen::Matrix3d F =
      (Eigen::Matrix3d::Identity() - V_sum / static_cast<double>(n)).inverse() /
      static_cast<double>(n);
  OiProblem p;
  p.T.setZero();
  for (size_t i = 0; i < n; ++i)
    p.T += F * (V[i] - Eigen::Matrix3d::Identity()) * kron_row(c.plane_points[i]);
  // q_i = V_i (R P_i + t(R)); M = sum_i q_i (P_i - P_mean)^T, so
  // vec(M) = sum_i ((P_i - P_mean) kron I3) V_i (kron_row(P_i) + T) vec(R).
  p.L.setZero();
  p.G.setZero();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Matrix<double, 3, 6> RP_plus_t = kron_row(c.plane_points[i]) + p.T;
    const Eigen::Matrix<double, 3, 6> q_of_r = V[i] * RP_plus_t;
    const Eigen::Vector2d d = c.plane_points[i] - P_mean;
    p.L.topRows<3>() += d.x() * q_of_r;
    p.L.bottomRows<3>() += d.y() * q_of_r;
    const Eigen::Matrix<double, 3, 6> e_of_r = RP_plus_t - q_of_r;  // eq. 9
    p.G += e_of_r.transpose() * e_of_r;
  }
  return p;
}

Vector6d6 vec(const Matrix32d& R) {
  return Eigen::Map<const Vector6d6>(R.data());
}
Matrix32d mat(const Vector6d6& v) {
  return Eigen::Map<const Matrix32d>(v.data());
}

double error_of(const OiProblem& p, const Matrix32d& R) {
  const Vector6d6 r = vec(R);
  return r.dot(p.G * r);
}

// The orthonormal pair nearest to M (orthogonal Procrustes): M (M^T M)^-1/2,
// with the 2x2 square root in closed form, sqrt(B) = (B + sqrt(det B) I) /
// sqrt(tr B + 2 sqrt(det B)). A rank-deficient M (never from OI's data) falls
// back to the SVD.
Matrix32d nearest_orthonormal_pair(const Matrix32d& M) {
  const Eigen::Matrix2d B = M.transpose() * M;
  const double det = B.determinant();
  if (!(det > 1e-24 * B.trace() * B.trace())) {
    const Eigen::JacobiSVD<Matrix32d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
    return svd.matrixU().leftCols<2>() * svd.matrixV().transpose();
  }
  const double s = std::sqrt(det);
  const Eigen::Matrix2d sqrt_B =
      (B + s * Eigen::Matrix2d::Identity()) / std::sqrt(B.trace() + 2 * s);
  return M * sqrt_B.inverse();
}

Eigen::Matrix3d complete_rotation(const Matrix32d& R) {
  Eigen::Matrix3d out;
  out << R, R.col(0).cross(R.col(1));
  return out;
}

// Weak-perspective start for planar points (Lu et al. §4.4, planar case): fit
// the affine map from plane to normalized image, x = A X + b, and complete its
// 2x2 block s R_2x2 to a rotation. The missing third-row entries (p, q) of the
// first two columns satisfy p^2 - q^2 = |b|^2 - |a|^2 and p q = -a.b (equal
// column norms, orthogonal columns), so p + i q = +-sqrt(|b|^2 - |a|^2 - 2i a.b):
// the planar two-fold ambiguity. Returns both rotations R_cam_plane.
std::array<Eigen::Matrix3d, 2> weak_perspective_rotations(const Correspondences& c) {
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Matrix<double, 3, 2> rhs = Eigen::Matrix<double, 3, 2>::Zero();
  for (size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector3d X = c.plane_points[i].homogeneous();
    normal += X * X.transpose();
    rhs += X * c.normalized[i].transpose();
  }
  const Eigen::Matrix<double, 3, 2> affine = normal.ldlt().solve(rhs);  // rows: X, Y, 1
  const Eigen::Vector2d a = affine.row(0).transpose();  // image of the plane's x axis
  const Eigen::Vector2d b = affine.row(1).transpose();  // image of the plane's y axis
  const std::complex<double> w =
      std::sqrt(std::complex<double>(b.squaredNorm() - a.squaredNorm(), -2.0 * a.dot(b)));
  std::array<Eigen::Matrix3d, 2> out;
  for (int k = 0; k < 2; ++k) {
    const double sign = k == 0 ? 1.0 : -1.0;
    Eigen::Matrix3d R;
    R.col(0) = Eigen::Vector3d(a.x(), a.y(), sign * w.real()).normalized();
    R.col(1) = Eigen::Vector3d(b.x(), b.y(), sign * w.imag()).normalized();
    R.col(2) = R.col(0).cross(R.col(1));
    out[k] = nearest_rotation(R);
  }
  return out;
}

// The other planar minimum (Schweighofer & Pinz, "Robust pose estimation from
// a planar target", IEEE PAMI 28(12), 2006; Collins & Bartoli 2014, eq. 18):
// in the frame whose z axis is the line of sight to the points' centre, the
// two minima differ in the sign of the z components of the plane's x and y
// axes. T is T_cam_plane; so is the result's rotation.
Eigen::Matrix3d mirrored_start(const Correspondences& c, const Pose& T) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& P : c.plane_points)
    centre += T * Eigen::Vector3d(P.x(), P.y(), 0);
  const Eigen::Vector3d d = centre.normalized();
  const Eigen::Matrix3d Rv =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), d).toRotationMatrix();
  Matrix32d in_ray = Rv.transpose() * T.R.leftCols<2>();
  in_ray.row(2) *= -1;
  return complete_rotation(Rv * in_ray);
}

Eigen::Matrix3d skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d S;
  S << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return S;
}

// Newton steps after OI's cap; a strict minimum is reached in a few.
constexpr int kNewtonSteps = 20;

// Newton's method on the same E, for where OI crawls: near frontal the two
// planar minima merge, E is nearly flat between them and OI's linear rate
// tends to 1 (thousands of steps). With R(w) = exp([w]x) R, vec(R(w)) is, to
// second order, vec(R + [w]x R + [w]x^2 R / 2), so E's gradient and Hessian
// in w are exact at w = 0 from G. Each step is kept only when it lowers E, so
// the minimum reached is OI's own. Returns whether it reached a strict
// minimum (positive-definite Hessian) to rounding, or E's rounding floor
// (noise-free data). Near frontal E is so flat across the valley (smallest
// curvature ~1e-4 of the largest) that rounding, not the step's length, ends
// the descent: the model's remaining decrease g^T H^-1 g / 2 falls below
// the last bit of E, or below the rounding of vec(R)^T G vec(R) where no
// step lowers E any more.
bool newton_finish(const OiProblem& p, double floor, Matrix32d* R, double* error, int max_steps,
                   int* steps_taken) {
  constexpr double step_tolerance_rad = 1e-11;
  for (int k = 0; k < max_steps; ++k) {
    ++*steps_taken;
    std::array<Eigen::Matrix3d, 3> E;
    for (int i = 0; i < 3; ++i)
      E[i] = skew(Eigen::Vector3d::Unit(i));
    const Vector6d6 r = vec(*R);
    std::array<Vector6d6, 3> d;
    for (int i = 0; i < 3; ++i)
      d[i] = vec(E[i] * *R);
    Eigen::Vector3d g;
    Eigen::Matrix3d H;
    for (int i = 0; i < 3; ++i) {
      g(i) = 2 * r.dot(p.G * d[i]);
      for (int j = 0; j < 3; ++j) {
        const Vector6d6 s = vec(0.5 * (E[i] * E[j] + E[j] * E[i]) * *R);
        H(i, j) = 2 * d[i].dot(p.G * d[j]) + 2 * r.dot(p.G * s);
      }
    }
    // Where E is not convex (between the two minima) the Hessian is shifted
    // to positive definite, turning the step towards steepest descent.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(H);
    const Eigen::Vector3d lambda = eig.eigenvalues();
    const double shift = lambda(0) > 1e-9 * lambda(2) ? 0.0 : 1e-6 * lambda(2) - lambda(0);
    const bool strict_minimum = shift == 0.0;
    const Eigen::Vector3d g_eigen = eig.eigenvectors().transpose() * g;
    const Eigen::Vector3d w =
        -eig.eigenvectors() * (g_eigen.array() / (lambda.array() + shift)).matrix();
    const double angle = w.norm();
    constexpr double eps = std::numeric_limits<double>::epsilon();
    const double remaining = 0.5 * -g.dot(w);  // the model's decrease to its minimum
    if (strict_minimum &&
        (angle < step_tolerance_rad || remaining <= eps * *error || *error <= floor))
      return true;
    // Backtracking: in the flat valley E is far from quadratic over a full
    // step; halving until E drops keeps every accepted step a descent.
    bool lowered = false;
    for (double scale = 1; scale > 1e-6 && !lowered; scale *= 0.5) {
      const Eigen::Matrix3d turn = Eigen::AngleAxisd(scale * angle, w / angle).toRotationMatrix();
      const Matrix32d next = nearest_orthonormal_pair(turn * *R);
      const double next_error = error_of(p, next);
      if (next_error < *error) {
        *R = next;
        *error = next_error;
        lowered = true;
      }
    }
    if (!lowered) {
      const double rounding = eps * r.cwiseAbs().dot(p.G.cwiseAbs() * r.cwiseAbs());
      return strict_minimum && (angle < 1e3 * step_tolerance_rad || remaining <= rounding);
    }
  }
  return false;
}

}  // namespace

namespace {

// OI on prepared constants; see orthogonal_iteration.
Estimate iterate(const OiProblem& p, const Correspondences& c, const Eigen::Matrix3d& R_start,
                 const OiOptions& options, double* object_space_error_out) {
  // One OI step (Lu et al. §3.2): absolute orientation between the object
  // points and their projections on the lines of sight, i.e. the rotation
  // nearest to the cross-covariance M(R).
  auto step = [&p](const Matrix32d& R) { return nearest_orthonormal_pair(mat(p.L * vec(R))); };
  Estimate e;
  const Eigen::Matrix3d R_target_plane = c.T_target_plane.R;
  Matrix32d R = (R_start * R_target_plane).leftCols<2>();
  double error = error_of(p, R);
  // Below this E (m^2) the residual is at the rounding level of the points
  // themselves: nothing is left to minimise (noise-free data).
  const double floor = 1e-28 * static_cast<double>(c.size());
  e.termination = Termination::kMaxIterations;
  int steps = 0;
  while (steps < options.max_iterations) {
    // OI converges linearly, slowly when depth and rotation are weakly
    // coupled (a small target far away). SQUAREM (Varadhan & Roland, Scand. J.
    // Statist. 35, 2008, scheme S3) extrapolates two OI steps along their
    // first and second differences; the result is projected back onto the
    // rotations and followed by one OI step. It has the same fixed points,
    // and is kept only when it lowers E below the plain two steps' E.
    const Matrix32d R1 = step(R), R2 = step(R1);
    steps += 2;
    Matrix32d next = R2;
    double next_error = error_of(p, R2);
    const Matrix32d r = R1 - R, v = R2 - 2 * R1 + R;
    if (options.accelerate && v.norm() > 0) {
      const double alpha = std::min(-1.0, -r.norm() / v.norm());
      const Matrix32d R_extrapolated =
          step(nearest_orthonormal_pair(R - 2 * alpha * r + alpha * alpha * v));
      ++steps;
      const double extrapolated_error = error_of(p, R_extrapolated);
      if (extrapolated_error < next_error) {
        next = R_extrapolated;
        next_error = extrapolated_error;
      }
    }
    const bool stalled = error - next_error <= options.relative_tolerance * error;
    R = next;
    error = std::min(error, next_error);
    if (stalled || error <= floor) {
      e.termination = Termination::kConverged;
      break;
    }
  }
  if (e.termination != Termination::kConverged &&
      newton_finish(p, floor, &R, &error, kNewtonSteps, &steps))
    e.termination = Termination::kConverged;
  e.iterations = steps;
  const Pose T_cam_plane{complete_rotation(R), p.T * vec(R)};
  e.T_cam_target = T_cam_plane * c.T_target_plane.inverse();
  e.converged = e.termination == Termination::kConverged;
  if (!e.converged)
    e.message = "no convergence in " + std::to_string(options.max_iterations) + " iterations";
  if (object_space_error_out) *object_space_error_out = error;
  return e;
}

}  // namespace

Estimate orthogonal_iteration(const Correspondences& c, const Eigen::Matrix3d& R_start,
                              const OiOptions& options, double* object_space_error_out) {
  return iterate(prepare(c), c, R_start, options, object_space_error_out);
}

namespace {

// OI from `start`, then from the other planar minimum of its result; the lower
// object-space error wins. Iterations of both runs are counted.
Estimate oi_with_mirror(const OiProblem& p, const Correspondences& c, const Eigen::Matrix3d& start,
                        const OiOptions& options) {
  double error = 0, mirror_error = 0;
  Estimate e = iterate(p, c, start, options, &error);
  const Pose T_cam_plane = e.T_cam_target * c.T_target_plane;
  const Eigen::Matrix3d mirror_R_cam_target =
      mirrored_start(c, T_cam_plane) * c.T_target_plane.R.transpose();
  Estimate m = iterate(p, c, mirror_R_cam_target, options, &mirror_error);
  const int iterations = e.iterations + m.iterations;
  const bool mirror_better = (m.converged || !e.converged) && mirror_error < error &&
                             in_front_of_camera(c, m.T_cam_target);
  Estimate& best = mirror_better ? m : e;
  best.iterations = iterations;
  return best;
}

}  // namespace

Estimate OiSolver::solve_pose(const Correspondences& c, const SolverHint& hint) const {
  const OiProblem p = prepare(c);
  if (hint.T_cam_target) return oi_with_mirror(p, c, hint.T_cam_target->R, options_);
  // Lu et al.'s own start: weak perspective; of its two planar rotations the
  // one with the lower object-space error, then its mirror.
  const auto starts = weak_perspective_rotations(c);
  const Eigen::Matrix3d& start =
      error_of(p, starts[0].leftCols<2>()) <= error_of(p, starts[1].leftCols<2>()) ? starts[0]
                                                                                   : starts[1];
  return oi_with_mirror(p, c, start * c.T_target_plane.R.transpose(), options_);
}

Estimate HybridOiSolver::solve_pose(const Correspondences& c, const SolverHint& hint) const {
  Pose start;
  std::string why;
  if (hint.T_cam_target) {
    start = *hint.T_cam_target;
  } else if (!c.square_side_m) {
    return unsolved(Termination::kNotApplicable,
                    "hybrid_oi starts from the analytic pose of a square: the first four object "
                    "points are not a square A, B, C, D");
  } else if (!analytic_square_pose(c, &start, &why)) {
    return unsolved(Termination::kDegenerate, "analytic start failed: " + why);
  }
  // The analytic start is on the right side of the planar ambiguity except
  // near it, where OI follows it to the nearer minimum; that is the hybrid of
  // the paper (§2.2), so no mirror start here.
  return orthogonal_iteration(c, start.R, options_, nullptr);
}

}  // namespace vision
