#include "vision/pose_ekf.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <utility>

#include "vision/pose_analytic.hpp"

namespace vision {
namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;

Pose pose_from_state(const Vector6d& x) {
  return {rotation_from_euler_zyx(x(0), x(1), x(2)), x.tail<3>()};
}

Vector6d state_from_pose(const Pose& T) {
  Vector6d x;
  x << euler_zyx_from_rotation(T.R), T.t;
  return x;
}

// The difference of two states with the angles wrapped to (-pi, pi], so that a
// prior at psi = pi and a state at -pi are not 2 pi apart: std::remainder(d,
// 2 pi), with its two common cases written out. For |d| <= pi it is d; for
// pi < |d| < 3 pi it is d -+ 2 pi, which is exact in floating point (Sterbenz:
// d and 2 pi are within a factor of 2), so all three give the same bits.
Vector6d state_difference(const Vector6d& a, const Vector6d& b) {
  constexpr double two_pi = 2.0 * M_PI;
  Vector6d d = a - b;
  for (int k = 0; k < 3; ++k) {
    const double m = std::abs(d(k));
    if (m <= M_PI) continue;
    d(k) = m < 3 * M_PI ? d(k) - std::copysign(two_pi, d(k)) : std::remainder(d(k), two_pi);
  }
  return d;
}

// Eqs. 15-17 and 29: the measurement residual z - h(x) (undistorted pixels)
// and its Jacobian H = dh/dx, accumulated straight into H^T H and H^T r (the
// only products the update needs). With R = Rz(psi) Ry(theta) Rx(phi) and
// Q = Ry Rx P: dR/dpsi P = e_z x (R P) = (-(RP)_y, (RP)_x, 0),
// dR/dtheta P = Rz (e_y x Q) = (cos psi Q_z, sin psi Q_z, -Q_x),
// dR/dphi P = R (e_x x P) = R (0, -P_z, P_y). The two rows of dh/dp are
// fx/z (1, 0, -u) and fy/z (0, 1, -v) (u, v the projected point), so each row
// of H is a handful of products, accumulated at fixed size.
// Returns false when a point is on or behind the camera.
bool measurement(const Correspondences& c, const Vector6d& x, Matrix6d* HtH, Vector6d* Htr,
                 double* residual_squared) {
  const Intrinsics& k = c.camera->intrinsics();
  const double cz = std::cos(x(0)), sz = std::sin(x(0)), cy = std::cos(x(1)), sy = std::sin(x(1)),
               cx = std::cos(x(2)), sx = std::sin(x(2));
  // Ry Rx and R = Rz Ry Rx, written out.
  Eigen::Matrix3d RyRx, R;
  RyRx << cy, sy * sx, sy * cx, 0, cx, -sx, -sy, cy * sx, cy * cx;
  R.row(0) = cz * RyRx.row(0) - sz * RyRx.row(1);
  R.row(1) = sz * RyRx.row(0) + cz * RyRx.row(1);
  R.row(2) = RyRx.row(2);
  const Eigen::Vector3d t = x.tail<3>();
  Matrix6d A = Matrix6d::Zero();
  Vector6d g = Vector6d::Zero();
  double sum_sq = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector3d& P = c.object_points[i];
    const Eigen::Vector3d Q = RyRx * P;
    const Eigen::Vector3d RP(cz * Q.x() - sz * Q.y(), sz * Q.x() + cz * Q.y(), Q.z());
    const Eigen::Vector3d p = RP + t;
    if (!(p.z() > 0)) return false;
    const double inv_z = 1.0 / p.z();
    const double u = p.x() * inv_z, v = p.y() * inv_z;
    // Observed undistorted pixel minus predicted pixel.
    const double r0 = k.fx * (c.normalized[i].x() - u), r1 = k.fy * (c.normalized[i].y() - v);
    const Eigen::Vector3d d_phi = R.col(2) * P.y() - R.col(1) * P.z();
    const double ax = k.fx * inv_z, by = k.fy * inv_z;
    // The two rows of H: d(u, v)/d(psi, theta, phi, tx, ty, tz), pixels.
    Vector6d h0, h1;
    h0 << ax * (-RP.y()), ax * (cz * Q.z() + u * Q.x()), ax * (d_phi.x() - u * d_phi.z()), ax, 0,
        -ax * u;
    h1 << by * RP.x(), by * (sz * Q.z() + v * Q.x()), by * (d_phi.y() - v * d_phi.z()), 0, by,
        -by * v;
    // One outer product at a time: Eigen evaluates each in place, column by
    // column in packed (SIMD) pairs, with no temporary.
    A.noalias() += h0 * h0.transpose();
    A.noalias() += h1 * h1.transpose();
    g += r0 * h0;
    g += r1 * h1;
    sum_sq += r0 * r0 + r1 * r1;
  }
  *HtH = A;
  *Htr = g;
  *residual_squared = sum_sq;
  return true;
}

// The inverse of a symmetric 3x3 matrix in closed form (adjugate over
// determinant); false when it is not invertible.
bool inverse3_symmetric(const Eigen::Matrix3d& m, Eigen::Matrix3d* inv) {
  const double c00 = m(1, 1) * m(2, 2) - m(1, 2) * m(1, 2);
  const double c01 = m(0, 2) * m(1, 2) - m(0, 1) * m(2, 2);
  const double c02 = m(0, 1) * m(1, 2) - m(0, 2) * m(1, 1);
  const double det = m(0, 0) * c00 + m(0, 1) * c01 + m(0, 2) * c02;
  if (!(std::abs(det) > 0) || !std::isfinite(det)) return false;
  const double s = 1.0 / det;
  const double c11 = m(0, 0) * m(2, 2) - m(0, 2) * m(0, 2);
  const double c12 = m(0, 1) * m(0, 2) - m(0, 0) * m(1, 2);
  const double c22 = m(0, 0) * m(1, 1) - m(0, 1) * m(0, 1);
  *inv << c00 * s, c01 * s, c02 * s, c01 * s, c11 * s, c12 * s, c02 * s, c12 * s, c22 * s;
  return true;
}

// A symmetric positive-definite 6x6 system in 3x3 blocks (angles, translation),
// A = [A11 A12; A12^T A22], eliminated through the Schur complement
// S = A22 - A12^T A11^-1 A12 with both 3x3 inverses in closed form: no
// pivoting (the blocks of a positive-definite matrix and its Schur complement
// are positive definite), two divisions, short dependency chains.
struct Spd6 {
  Eigen::Matrix3d inv11, inv_schur, W;  // W = A11^-1 A12
  Eigen::Matrix3d A21;
  bool ok = false;

  explicit Spd6(const Matrix6d& A) {
    const Eigen::Matrix3d A11 = A.topLeftCorner<3, 3>();
    A21 = A.bottomLeftCorner<3, 3>();
    if (!inverse3_symmetric(A11, &inv11)) return;
    W = inv11 * A21.transpose();
    const Eigen::Matrix3d schur = A.bottomRightCorner<3, 3>() - A21 * W;
    ok = inverse3_symmetric(schur, &inv_schur);
  }
  Vector6d solve(const Vector6d& b) const {
    const Eigen::Vector3d y1 = inv11 * b.head<3>();
    const Eigen::Vector3d x2 = inv_schur * (b.tail<3>() - A21 * y1);
    Vector6d x;
    x << y1 - W * x2, x2;
    return x;
  }
};

// A^-1 b for the symmetric positive-definite A (LDLT when a block is singular).
Vector6d solve_spd(const Matrix6d& A, const Vector6d& b) {
  const Spd6 blocks(A);
  if (blocks.ok) return blocks.solve(b);
  return A.ldlt().solve(b);
}

// A^-1 of the symmetric positive-definite A, column by column.
Matrix6d inverse_spd(const Matrix6d& A) {
  const Spd6 blocks(A);
  if (!blocks.ok) return A.ldlt().solve(Matrix6d::Identity());
  Matrix6d inverse;
  for (int j = 0; j < 6; ++j)
    inverse.col(j) = blocks.solve(Vector6d::Unit(j));
  return inverse;
}

Matrix6d diagonal_covariance(double sigma_angle, double sigma_translation) {
  Vector6d d;
  d << Eigen::Vector3d::Constant(sigma_angle * sigma_angle),
      Eigen::Vector3d::Constant(sigma_translation * sigma_translation);
  return d.asDiagonal();
}

// The measurement system at one state and the filter's cost there.
struct Linearisation {
  Matrix6d HtH;
  Vector6d Htr;
  double cost = 0;
};

// The filter's MAP cost, which the update minimises:
//   inv_r |z - h(x)|^2 + (x - x_prior)^T P^-1 (x - x_prior).
struct MapCost {
  const Correspondences& c;
  Vector6d x_prior;
  Matrix6d prior_information;  // P^-1
  double inv_r;                // R^-1 = 1 / sigma^2, px^-2

  // False when a point is on or behind the camera.
  bool evaluate(const Vector6d& state, Linearisation* at) const {
    double residual_squared = 0;
    if (!measurement(c, state, &at->HtH, &at->Htr, &residual_squared)) return false;
    const Vector6d d = state_difference(state, x_prior);
    at->cost = inv_r * residual_squared + d.dot(prior_information * d);
    return true;
  }
};

MapCost map_cost(const Correspondences& c, const Pose& prior, const Matrix6d& prior_covariance,
                 const EkfOptions& options) {
  return {c, state_from_pose(prior), inverse_spd(prior_covariance),
          1.0 / (options.measurement_sigma_px * options.measurement_sigma_px)};
}

// Levenberg-Marquardt damping of the Gauss-Newton step and its schedule,
// carried from one iteration to the next.
struct Damping {
  double lambda = 1e-6;
  double growth = 2;
};

struct DampedStep {
  Vector6d step = Vector6d::Zero();  // not finite when the damped system is singular
  bool accepted = false;             // it lowers the cost; `*next` is the state it reaches
};

// The least-damped step from x that lowers the cost (`at` is the system at
// x, `information` and `gradient` the update's). The gain ratio of the actual
// to the predicted decrease of the cost (the model is cost - 2 s.g + s.I.s)
// sets the damping by Nielsen's rule (Madsen, Nielsen & Tingleff 2004, eq.
// 2.21), which stops the zig-zag of full steps across the curved valley
// between planar poses. `next` receives the system at x + step (written in
// place: the caller swaps it with `at`, no 6x6 copies per iteration).
DampedStep damped_step(const MapCost& map, const Vector6d& x, const Linearisation& at,
                       const Matrix6d& information, const Vector6d& gradient, Damping* damping,
                       Linearisation* next) {
  DampedStep out;
  while (damping->lambda <= 1e10) {
    Matrix6d damped = information;
    damped.diagonal() *= 1.0 + damping->lambda;
    out.step = solve_spd(damped, gradient);
    if (!out.step.allFinite()) break;
    const double predicted = 2 * out.step.dot(gradient) - out.step.dot(information * out.step);
    // A step the model does not predict to lower the cost is refused without
    // evaluating it.
    if (predicted > 0 && map.evaluate(x + out.step, next) && next->cost <= at.cost) {
      const double gain = (at.cost - next->cost) / predicted;
      if (gain > 0) {
        out.accepted = true;
        const double ratio = 2 * gain - 1;
        damping->lambda *= std::max(1.0 / 3.0, 1.0 - ratio * ratio * ratio);
        damping->growth = 2;
        break;
      }
    }
    damping->lambda *= damping->growth;
    damping->growth *= 2;
  }
  return out;
}

// Converged or not, and why, once the iterations have stopped at state x.
// Consistency gate: a state that explains the corners far worse than the
// measurement noise allows is a wrong local minimum, not a pose.
void settle_termination(const Correspondences& c, const Vector6d& x, const EkfOptions& options,
                        Estimate* e) {
  if (e->termination == Termination::kConverged) {
    Matrix6d HtH;
    Vector6d Htr;
    double residual_squared = 0;
    measurement(c, x, &HtH, &Htr, &residual_squared);
    const double rms = std::sqrt(residual_squared / (2.0 * static_cast<double>(c.size())));
    if (rms > options.gate_sigmas * options.measurement_sigma_px) {
      e->message = "converged to a state whose residual (" + std::to_string(rms) +
                   " px RMS per coordinate) exceeds the gate of " +
                   std::to_string(options.gate_sigmas) + " measurement sigmas: a local minimum";
      e->termination = Termination::kLocalMinimum;
      e->converged = false;
      return;
    }
    e->converged = true;
  } else if (e->termination == Termination::kMaxIterations) {
    e->message = "the state was still moving after " + std::to_string(options.max_iterations) +
                 " iterations";
  }
}

}  // namespace

Estimate iterated_ekf(const Correspondences& c, const Pose& prior, const Matrix6d& prior_covariance,
                      const EkfOptions& options) {
  // Measurement update (eqs. 25-28), relinearised about the current state until
  // it stops moving. Written in information form, which gives the same state
  // and covariance as the gain form (K = P H^T (H P H^T + R)^-1) while inverting
  // a 6x6 matrix instead of a 2N x 2N one:
  //   P+ = (P^-1 + H^T R^-1 H)^-1,
  //   x_{i+1} = x_i + P+ (H^T R^-1 (z - h(x_i)) - P^-1 (x_i - x_prior)).
  // The update minimises the filter's MAP cost; a Gauss-Newton step that
  // would raise it (a poor start, or the curved valley between the two planar
  // poses) is damped Levenberg-Marquardt style instead of taken: the damped
  // iterated EKF (Bell & Cathey 1993 view the IEKF as Gauss-Newton), same
  // fixed point and posterior covariance.
  const MapCost map = map_cost(c, prior, prior_covariance, options);
  Estimate e;
  Vector6d x = map.x_prior;
  Matrix6d information = map.prior_information;
  Linearisation systems[2];
  Linearisation *at = &systems[0], *next = &systems[1];
  Damping damping;
  e.termination = Termination::kMaxIterations;
  if (!map.evaluate(x, at)) {
    e.termination = Termination::kBehindCamera;
    e.message = "the prior state puts an object point behind the camera";
  }
  for (int it = 1; it <= options.max_iterations && e.termination == Termination::kMaxIterations;
       ++it) {
    e.iterations = it;
    information = map.prior_information + map.inv_r * at->HtH;
    const Vector6d gradient =
        map.inv_r * at->Htr - map.prior_information * state_difference(x, map.x_prior);
    const DampedStep d = damped_step(map, x, *at, information, gradient, &damping, next);
    if (!d.step.allFinite()) {
      e.termination = Termination::kNumericalFailure;
      e.message = "the measurement update is singular";
      break;
    }
    if (!d.accepted || d.step.cwiseAbs().maxCoeff() <= options.state_tolerance) {
      // No step lowers the cost any more, or the step is negligible: the
      // minimum, to rounding.
      e.termination = Termination::kConverged;
      if (d.accepted) x += d.step;
      break;
    }
    x += d.step;
    std::swap(at, next);
  }
  e.T_cam_target = pose_from_state(x);
  e.covariance = inverse_spd(information);
  settle_termination(c, x, options, &e);
  return e;
}

namespace {

// Prior from a carried state: the time update of eqs. 18-20 (A = I, P += Q).
Matrix6d carried_covariance(const SolverHint& hint, const EkfOptions& o) {
  const Matrix6d Q = diagonal_covariance(o.process_sigma_angle_rad, o.process_sigma_translation_m);
  return hint.covariance
             ? Matrix6d(*hint.covariance + Q)
             : diagonal_covariance(o.prior_sigma_angle_rad, o.prior_sigma_translation_m);
}

}  // namespace

Estimate EkfSolver::solve_pose(const Correspondences& c, const SolverHint& hint) const {
  if (hint.T_cam_target)
    return iterated_ekf(c, *hint.T_cam_target, carried_covariance(hint, options_), options_);
  const Pose nominal{Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, options_.prior_depth_m)};
  return iterated_ekf(
      c, nominal,
      diagonal_covariance(options_.prior_sigma_angle_rad, options_.prior_sigma_translation_m),
      options_);
}

Estimate HybridEkfSolver::solve_pose(const Correspondences& c, const SolverHint& hint) const {
  if (hint.T_cam_target)
    return iterated_ekf(c, *hint.T_cam_target, carried_covariance(hint, options_), options_);
  if (!c.square_side_m)
    return unsolved(Termination::kNotApplicable,
                    "hybrid_ekf starts from the analytic pose of a square: the first four object "
                    "points are not a square A, B, C, D");
  Pose start;
  std::string why;
  if (!analytic_square_pose(c, &start, &why))
    return unsolved(Termination::kDegenerate, "analytic start failed: " + why);
  return iterated_ekf(
      c, start,
      diagonal_covariance(options_.prior_sigma_angle_rad, options_.prior_sigma_translation_m),
      options_);
}

}  // namespace vision
