// The iterated EKF (Maidi et al. 2010, §2.3, eqs. 12-29; DOI
// 10.1007/s00138-008-0170-y) gives the same iterates as its straightforward
// first implementation, kept here as the reference: generic Eigen products
// for the Jacobian and H^T H, LDLT solves, std::remainder and std::pow. The
// solver's faster form (written-out rows of H, H^T H on one triangle, the
// 6x6 solve in 3x3 blocks, cheaper angle wrapping) is the same method in
// another order of floating-point operations.
//
// The k-th iterate of either is its result with max_iterations = k, so every
// iterate is compared, not only the last. Where the reference converges
// (every run from the analytic start, and the runs from the nominal prior
// that find the minimum) the two take the same number of iterations, and
// every iterate but the last agrees to 1e-9 (radians and metres). Why 1e-9:
// the two differ only in the order of floating-point operations; a step is
// solved from a 6x6 system whose condition number here stays below ~1e6, so
// each step is reproduced to ~1e-16 x 1e6 relative, ~1e-11 of steps of at
// most ~0.1 (measured: 1e-13 at worst). The last iterate may differ by up to
// the stopping rule's state_tolerance (1e-7): the final step is below it, and
// whether it lowers the cost is decided at the rounding level of the cost,
// so one implementation may take it and the other not (measured: 1.3e-8).
//
// From the fixed nominal prior most runs do not converge: they crawl along
// the flat valley between the planar poses until max_iterations. There the
// accept/reject decisions of the damping compare costs equal to rounding, so
// the two paths (like any two orderings of the same arithmetic) separate
// after 4-40 iterations. For those runs the test holds what is defined: the
// same termination and iteration count, and the same first three iterates.
// Seeded problems (0.5 px corner noise, 0.1-1.0 m, tilt up to 60 degrees), so
// the outcome is fixed. Every comparison runs each build of the solver's inner
// loops the CPU runs (vision::EkfInstructionSet): the baseline one, and the
// AVX2 and FMA one (four corners a register, fused multiply-adds) where the CPU
// has it; both are held to the same reference.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <random>

#include "synthetic_pose.hpp"
#include "vision/correspondences.hpp"
#include "vision/pose_analytic.hpp"
#include "vision/pose_ekf.hpp"

namespace ekf_reference {

using namespace vision;

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
// prior at psi = pi and a state at -pi are not 2 pi apart.
Vector6d state_difference(const Vector6d& a, const Vector6d& b) {
  Vector6d d = a - b;
  for (int k = 0; k < 3; ++k)
    d(k) = std::remainder(d(k), 2.0 * M_PI);
  return d;
}

// Eqs. 15-17 and 29: the measurement residual z - h(x) (undistorted pixels)
// and its Jacobian H = dh/dx, accumulated straight into H^T H and H^T r (the
// only products the update needs). With R = Rz(psi) Ry(theta) Rx(phi):
// dR/dpsi P = e_z x (R P), dR/dtheta P = Rz (e_y x (Ry Rx P)), dR/dphi P = R (e_x x P).
// Returns false when a point is on or behind the camera.
bool measurement(const Correspondences& c, const Vector6d& x, Matrix6d* HtH, Vector6d* Htr,
                 double* residual_squared) {
  const Intrinsics& k = c.camera->intrinsics();
  const double cz = std::cos(x(0)), sz = std::sin(x(0)), cy = std::cos(x(1)), sy = std::sin(x(1)),
               cx = std::cos(x(2)), sx = std::sin(x(2));
  Eigen::Matrix3d Rz, Ry, Rx;
  Rz << cz, -sz, 0, sz, cz, 0, 0, 0, 1;
  Ry << cy, 0, sy, 0, 1, 0, -sy, 0, cy;
  Rx << 1, 0, 0, 0, cx, -sx, 0, sx, cx;
  const Eigen::Matrix3d RyRx = Ry * Rx;
  const Eigen::Matrix3d R = Rz * RyRx;
  HtH->setZero();
  Htr->setZero();
  *residual_squared = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector3d& P = c.object_points[i];
    const Eigen::Vector3d RP = R * P;
    const Eigen::Vector3d p = RP + x.tail<3>();
    if (!(p.z() > 0)) return false;
    const double inv_z = 1.0 / p.z();
    // Observed undistorted pixel minus predicted pixel.
    const Eigen::Vector2d r(k.fx * (c.normalized[i].x() - p.x() * inv_z),
                            k.fy * (c.normalized[i].y() - p.y() * inv_z));
    Eigen::Matrix<double, 2, 3> dh_dp;
    dh_dp << k.fx * inv_z, 0, -k.fx * p.x() * inv_z * inv_z, 0, k.fy * inv_z,
        -k.fy * p.y() * inv_z * inv_z;
    Eigen::Matrix3d dp_dangles;
    dp_dangles.col(0) = Eigen::Vector3d::UnitZ().cross(RP);
    dp_dangles.col(1) = Rz * Eigen::Vector3d::UnitY().cross(RyRx * P);
    dp_dangles.col(2) = R * Eigen::Vector3d::UnitX().cross(P);
    Eigen::Matrix<double, 2, 6> H;
    H.leftCols<3>() = dh_dp * dp_dangles;
    H.rightCols<3>() = dh_dp;
    *HtH += H.transpose() * H;
    *Htr += H.transpose() * r;
    *residual_squared += r.squaredNorm();
  }
  return true;
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
  const Eigen::LDLT<Matrix6d> prior_ldlt(prior_covariance);
  return {c, state_from_pose(prior), prior_ldlt.solve(Matrix6d::Identity()),
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
  bool accepted = false;             // it lowers the cost; `next` is the state it reaches
  Linearisation next;
};

// The least-damped step from x that lowers the cost (`at` is the system at
// x, `information` and `gradient` the update's). The gain ratio of the actual
// to the predicted decrease of the cost (the model is cost - 2 s.g + s.I.s)
// sets the damping by Nielsen's rule (Madsen, Nielsen & Tingleff 2004, eq.
// 2.21), which stops the zig-zag of full steps across the curved valley
// between planar poses.
DampedStep damped_step(const MapCost& map, const Vector6d& x, const Linearisation& at,
                       const Matrix6d& information, const Vector6d& gradient, Damping* damping) {
  DampedStep out;
  while (damping->lambda <= 1e10) {
    Matrix6d damped = information;
    damped.diagonal() *= 1.0 + damping->lambda;
    out.step = damped.ldlt().solve(gradient);
    if (!out.step.allFinite()) break;
    const double predicted = 2 * out.step.dot(gradient) - out.step.dot(information * out.step);
    if (map.evaluate(x + out.step, &out.next) && out.next.cost <= at.cost && predicted > 0) {
      const double gain = (at.cost - out.next.cost) / predicted;
      if (gain > 0) {
        out.accepted = true;
        damping->lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2 * gain - 1, 3));
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
                   std::to_string(options.gate_sigmas) +
                   " measurement sigmas: a wrong local minimum, or corners that no one pose fits";
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
  Linearisation at;
  Damping damping;
  e.termination = Termination::kMaxIterations;
  if (!map.evaluate(x, &at)) {
    e.termination = Termination::kBehindCamera;
    e.message = "the prior state puts an object point behind the camera";
  }
  for (int it = 1; it <= options.max_iterations && e.termination == Termination::kMaxIterations;
       ++it) {
    e.iterations = it;
    information = map.prior_information + map.inv_r * at.HtH;
    const Vector6d gradient =
        map.inv_r * at.Htr - map.prior_information * state_difference(x, map.x_prior);
    DampedStep d = damped_step(map, x, at, information, gradient, &damping);
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
    at = d.next;
  }
  e.T_cam_target = pose_from_state(x);
  e.covariance = information.ldlt().solve(Matrix6d::Identity());
  settle_termination(c, x, options, &e);
  return e;
}

}  // namespace ekf_reference

namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;

constexpr double kTolerance = 1e-9;
constexpr int kCrawlCompared = 3;  // iterates compared on runs that do not converge

std::vector<vision::Correspondences> seeded_problems(const vision::Camera& camera,
                                                     bool whole_target, int count, uint64_t seed) {
  rig_test::ProblemSpec spec;
  spec.noise_px = 0.5;
  spec.whole_target = whole_target;
  std::mt19937_64 rng(seed);
  std::vector<vision::Correspondences> out;
  for (int i = 0; i < count; ++i) {
    const auto p = rig_test::draw_problem(camera, spec, rng);
    out.push_back(vision::make_correspondences(camera, p.object_points, p.image_points_px));
  }
  return out;
}

vision::Matrix6d prior_covariance(const vision::EkfOptions& o) {
  Vector6d d;
  d << Eigen::Vector3d::Constant(o.prior_sigma_angle_rad * o.prior_sigma_angle_rad),
      Eigen::Vector3d::Constant(o.prior_sigma_translation_m * o.prior_sigma_translation_m);
  return d.asDiagonal();
}

double pose_difference(const vision::Estimate& a, const vision::Estimate& b) {
  // |R1 - R2|_F / sqrt 2 is the angle between them to first order (acos of
  // the trace would lose digits below ~1e-8 rad).
  return std::max((a.T_cam_target.R - b.T_cam_target.R).norm() / std::sqrt(2.0),
                  (a.T_cam_target.t - b.T_cam_target.t).norm());
}

// Every iterate from `prior` on problem `c`, and the final estimate.
void compare_iterates_of(vision::EkfInstructionSet set, const vision::Correspondences& c,
                         const vision::Pose& prior, const std::string& name) {
  vision::EkfOptions options;
  options.instruction_set = set;
  const vision::Matrix6d P0 = prior_covariance(options);
  const vision::Estimate ref = ekf_reference::iterated_ekf(c, prior, P0, options);
  const vision::Estimate fast = vision::iterated_ekf(c, prior, P0, options);
  EXPECT_EQ(fast.iterations, ref.iterations) << name;
  EXPECT_EQ(fast.termination, ref.termination) << name;
  EXPECT_EQ(fast.converged, ref.converged) << name;
  const bool converged = ref.termination == vision::Termination::kConverged;
  const int compared = converged ? ref.iterations - 1 : std::min(ref.iterations, kCrawlCompared);
  vision::EkfOptions capped = options;
  for (int k = 1; k <= compared; ++k) {
    capped.max_iterations = k;
    EXPECT_LT(pose_difference(vision::iterated_ekf(c, prior, P0, capped),
                              ekf_reference::iterated_ekf(c, prior, P0, capped)),
              kTolerance)
        << name << " iterate " << k;
  }
  if (!converged) return;
  EXPECT_LT(pose_difference(fast, ref), options.state_tolerance) << name << " final";
  ASSERT_TRUE(fast.covariance && ref.covariance);
  // The covariance is the inverse of the information matrix at the final
  // state: the same to the rounding of a 6x6 inverse and the last step
  // (relative 1e-6 covers a step of 1e-7 through a Jacobian that varies on
  // the scale of the pose, ~0.1).
  EXPECT_LT((*fast.covariance - *ref.covariance).norm(), 1e-6 * ref.covariance->norm()) << name;
}

// compare_iterates_of for each build the CPU runs.
void compare_iterates(const vision::Correspondences& c, const vision::Pose& prior,
                      const std::string& name) {
  compare_iterates_of(vision::EkfInstructionSet::kBaseline, c, prior, name + " (baseline)");
  if (vision::cpu_runs(vision::EkfInstructionSet::kAvx2Fma))
    compare_iterates_of(vision::EkfInstructionSet::kAvx2Fma, c, prior, name + " (AVX2, FMA)");
}

// The hybrid's start (the analytic square pose) on the marker's 4 corners and
// on a 2x2 sheet's 16.
TEST(EkfReference, FastEkfFollowsTheReferenceIteratesFromTheAnalyticStart) {
  const vision::Camera camera = vision::Camera::paper_default();
  for (bool whole_target : {false, true}) {
    const auto problems = seeded_problems(camera, whole_target, 60, whole_target ? 31 : 29);
    for (size_t i = 0; i < problems.size(); ++i) {
      vision::Pose start;
      std::string why;
      ASSERT_TRUE(vision::analytic_square_pose(problems[i], &start, &why)) << why;
      compare_iterates(problems[i], start,
                       (whole_target ? "16pt problem " : "4pt problem ") + std::to_string(i));
    }
  }
}

// The plain EKF's fixed nominal prior (frontal at 0.5 m), from which it
// converges on some problems and crawls to max_iterations on the others.
TEST(EkfReference, FastEkfFollowsTheReferenceIteratesFromTheNominalPrior) {
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::EkfOptions options;
  const vision::Pose nominal{Eigen::Matrix3d::Identity(),
                             Eigen::Vector3d(0, 0, options.prior_depth_m)};
  const auto problems = seeded_problems(camera, false, 60, 37);
  for (size_t i = 0; i < problems.size(); ++i)
    compare_iterates(problems[i], nominal, "4pt problem " + std::to_string(i));
}

// Point counts that are not a multiple of the four the inner loops take at a
// time (the last block padded): the first 5, 6, 7 and 9 corners of 2x2
// sheets, from the analytic start of their first marker.
TEST(EkfReference, FastEkfFollowsTheReferenceIteratesOnAnyNumberOfPoints) {
  const vision::Camera camera = vision::Camera::paper_default();
  rig_test::ProblemSpec spec;
  spec.noise_px = 0.5;
  spec.whole_target = true;
  std::mt19937_64 rng(41);
  for (int i = 0; i < 12; ++i) {
    const auto p = rig_test::draw_problem(camera, spec, rng);
    for (size_t n : {5, 6, 7, 9}) {
      const std::vector<Eigen::Vector3d> object(p.object_points.begin(),
                                                p.object_points.begin() + n);
      const std::vector<Eigen::Vector2d> image(p.image_points_px.begin(),
                                               p.image_points_px.begin() + n);
      const vision::Correspondences c = vision::make_correspondences(camera, object, image);
      vision::Pose start;
      std::string why;
      ASSERT_TRUE(vision::analytic_square_pose(c, &start, &why)) << why;
      compare_iterates(c, start, std::to_string(n) + " points, problem " + std::to_string(i));
    }
  }
}

}  // namespace
