#include "vision/pose_ekf.hpp"

#include <cmath>
#include <utility>
#include <vector>

#include "ekf_measurement.hpp"
#include "vision/pose_analytic.hpp"

namespace vision {
namespace {

using detail::EkfPoints;
using detail::EulerTrig;
using detail::inverse_spd;
using detail::lower_triangle;
using detail::Symmetric6;
using detail::UpdateSystem;
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
// 2 pi), with its common cases written out. For |d| <= pi it is d; for
// pi < |d| < 3 pi it is d -+ 2 pi, which is exact in floating point (Sterbenz:
// d and 2 pi are within a factor of 2). Further out, d - k 2 pi with k the
// nearest integer to d / 2 pi is exactly representable (as every remainder
// is), so one fused multiply-add gives it exactly; when rounding of the
// quotient picked the wrong k, the result lands on or outside pi and
// std::remainder decides. All give the bits std::remainder gives.
Vector6d state_difference(const Vector6d& a, const Vector6d& b) {
  constexpr double two_pi = 2.0 * M_PI;
  Vector6d d = a - b;
  for (int k = 0; k < 3; ++k) {
    const double m = std::abs(d(k));
    if (m <= M_PI) continue;
    if (m < 3 * M_PI) {
      d(k) -= std::copysign(two_pi, d(k));
      continue;
    }
    const double wrapped = std::fma(-std::nearbyint(d(k) / two_pi), two_pi, d(k));
    d(k) = std::abs(wrapped) < M_PI ? wrapped : std::remainder(d(k), two_pi);
  }
  return d;
}

EulerTrig euler_trig(const Vector6d& x) {
  EulerTrig t{};
  for (int k = 0; k < 3; ++k) {
    t.s[k] = std::sin(x(k));
    t.c[k] = std::cos(x(k));
  }
  return t;
}

// sin s and cos s - 1 of three angles s (lanes 0-2) with |s| <= 1/4, by their
// Taylor series: the first omitted terms are below s^15 / 15! = 7e-22 and
// s^16 / 16! = 1.1e-23, so both are exact to a few units in the last place.
// Estrin's scheme (pairs of terms, then powers s^4 and s^8 of s^2): six
// multiplications deep instead of Horner's nine, on the chain from one
// trial state to the next. (Vectors pass by reference: by value, their
// calling convention would depend on the instruction set.)
inline void small_step_trig(const detail::Lanes& s, detail::Lanes* sin_s,
                            detail::Lanes* cos_s_minus_1) {
  const detail::Lanes s2 = s * s, s4 = s2 * s2, s8 = s4 * s4;
  const detail::Lanes sin_tail = (-1.0 / 6 + s2 * (1.0 / 120)) +
                                 s4 * (-1.0 / 5040 + s2 * (1.0 / 362880)) +
                                 s8 * (-1.0 / 39916800 + s2 * (1.0 / 6227020800));
  *sin_s = s + (s * s2) * sin_tail;
  *cos_s_minus_1 =
      s2 * ((-0.5 + s2 * (1.0 / 24)) + s4 * (-1.0 / 720 + s2 * (1.0 / 40320)) +
            s8 * ((-1.0 / 3628800 + s2 * (1.0 / 479001600)) + s4 * (-1.0 / 87178291200.0)));
}

// The sines and cosines at x + step from those at x, the three angles at
// once, a lane each: the angle-addition formulas sin(x + s) = sin x + (sin x
// (cos s - 1) + cos x sin s), likewise cos, with small_step_trig. When a
// step exceeds 1/4 rad (from the nominal prior, ~30 of a solve's ~230),
// all three are taken at s / 16 and doubled back four times: sin 2a = 2 sin
// a (1 + (cos a - 1)), cos 2a - 1 = -2 sin^2 a, a few units in the last
// place each. Each update is exact to ~1e-15; along the at most
// max_iterations steps of one solve that stays below ~1e-13, far inside the
// 1e-9 to which the iterates are defined
// (tests/vision/pose_ekf_reference_test.cpp). A step beyond 4 rad takes the
// sine and cosine of the new angle itself. About twenty vector multiply-adds
// for the three angles, against about 130 instructions for each of glibc's
// sincos (callgrind). Floating-point work costs the update time even off
// its chain (96 independent multiply-adds added to a trial cost it ~60
// cycles): the three lanes at once took about 2 % off a solve and the large
// steps without libm another 5 % (ABBA runs of bench_solvers).
inline EulerTrig euler_trig_after(const EulerTrig& at, const Vector6d& step, const Vector6d& next) {
  const detail::Lanes s = {step(0), step(1), step(2), 0.0};
  const double largest = step.head<3>().cwiseAbs().maxCoeff();
  detail::Lanes sin_s, cos_s_minus_1;
  if (largest <= 0.25) {
    small_step_trig(s, &sin_s, &cos_s_minus_1);
  } else {
    small_step_trig(s * (1.0 / 16), &sin_s, &cos_s_minus_1);
    for (int doubling = 0; doubling < 4; ++doubling) {
      const detail::Lanes sin_2s = 2.0 * sin_s * (1.0 + cos_s_minus_1);
      cos_s_minus_1 = -2.0 * sin_s * sin_s;
      sin_s = sin_2s;
    }
  }
  EulerTrig t;
  t.s = at.s + (at.s * cos_s_minus_1 + at.c * sin_s);
  t.c = at.c + (at.c * cos_s_minus_1 - at.s * sin_s);
  if (!(largest <= 4.0)) {
    for (int k = 0; k < 3; ++k) {
      if (!(std::abs(step(k)) <= 4.0)) {
        t.s[k] = std::sin(next(k));
        t.c[k] = std::cos(next(k));
      }
    }
  }
  return t;
}

Matrix6d diagonal_covariance(double sigma_angle, double sigma_translation) {
  Vector6d d;
  d << Eigen::Vector3d::Constant(sigma_angle * sigma_angle),
      Eigen::Vector3d::Constant(sigma_translation * sigma_translation);
  return d.asDiagonal();
}

// One state as the update sees it: the points projected there, the filter's
// cost, the prior's pull P^-1 (x - x_prior) (its gradient), the state's
// sines and cosines (the next trial state's start from them) and, once the
// update keeps the state, its system.
struct Linearisation {
  detail::EkfProjection projection;
  UpdateSystem system;
  Vector6d prior_pull;
  double cost = 0;
  EulerTrig trig;
};

// The filter's MAP cost, which the update minimises:
//   R^-1 |z - h(x)|^2 + (x - x_prior)^T P^-1 (x - x_prior).
struct MapCost {
  EkfPoints points;
  detail::EkfMeasurement measurement;
  Vector6d x_prior;
  Symmetric6 prior_information;  // P^-1
  // R^-1 = 1 / sigma^2 (px^-2, weights.inv_r) and P^-1 again, in the lanes
  // the measurement adds it to.
  detail::SystemWeights weights;
  // P^-1 has exact zeros off its diagonal (the nominal prior, the analytic
  // start): its product with a state difference is then the diagonal's, which
  // gives the same bits without the 30 products by zero (callgrind: 86.8k
  // instructions a nominal-prior solve with this path, 89.9k without).
  bool prior_is_diagonal;

  // The cost at `state`, whose sines and cosines `at->trig` already holds.
  // False when a point is on or behind the camera.
  bool evaluate(const Vector6d& state, Linearisation* at) const {
    if (!measurement.project(points, state, at->trig, &at->projection)) return false;
    const Vector6d d = state_difference(state, x_prior);
    at->prior_pull = prior_is_diagonal ? Vector6d(prior_information.diagonal().cwiseProduct(d))
                                       : prior_information * d;
    at->cost = weights.inv_r * at->projection.residual_squared + d.dot(at->prior_pull);
    return true;
  }
  // The update's system at a state evaluate() has costed (its information
  // P^-1 + R^-1 H^T H and R^-1 H^T r). Only for the states the update keeps:
  // a trial the update refuses needs its cost alone.
  void linearise(Linearisation* at) const {
    measurement.system(points, at->projection, weights, &at->system);
  }
  // Minus half the cost's gradient at a state, the way down: R^-1 H^T r - P^-1 (x - x_prior).
  Vector6d gradient(const Linearisation& at) const {
    return Eigen::Map<const Vector6d>(at.system.weighted_Htr) - at.prior_pull;
  }
};

MapCost map_cost(const Correspondences& c, const Pose& prior, const Matrix6d& prior_covariance,
                 const EkfOptions& options, EkfInstructionSet set) {
  const Symmetric6 covariance = lower_triangle(prior_covariance);
  // A diagonal P (the nominal prior, the analytic start) inverts entry by entry.
  Symmetric6 prior_information{};
  if (covariance.is_diagonal()) {
    for (int i = 0; i < 6; ++i)
      prior_information.lower[detail::lower_index(i, i)] = 1.0 / prior_covariance(i, i);
  } else {
    prior_information = lower_triangle(inverse_spd(covariance));
  }
  const double inv_r = 1.0 / (options.measurement_sigma_px * options.measurement_sigma_px);
  return {EkfPoints(c),
          detail::ekf_measurement(set),
          state_from_pose(prior),
          prior_information,
          detail::SystemWeights(prior_information, inv_r),
          prior_information.is_diagonal()};
}

// Levenberg-Marquardt damping of the Gauss-Newton step and its schedule,
// carried from one iteration to the next.
struct Damping {
  double lambda = 1e-6;
  double growth = 2;
};

struct DampedStep {
  Vector6d step = Vector6d::Zero();  // the step taken, when accepted
  bool accepted = false;             // it lowers the cost; `*next` is the state it reaches
  bool singular = false;             // a damped system's solution was not finite
};

// The least-damped step from x that lowers the cost (`at` is the system at
// x, `information` and `gradient` the update's). The gain ratio of the actual
// to the predicted decrease of the cost (the model is cost - 2 s.g + s.I.s)
// sets the damping by Nielsen's rule (Madsen, Nielsen & Tingleff 2004, eq.
// 2.21), which stops the zig-zag of full steps across the curved valley
// between planar poses. `next` receives the system at x + step (written in
// place: the caller swaps it with `at`, no 6x6 copies per iteration).
inline DampedStep damped_step(const MapCost& map, const Vector6d& x, const Linearisation& at,
                              const Symmetric6& information, const Vector6d& gradient,
                              Damping* damping, Linearisation* next) {
  DampedStep out;
  const Vector6d diagonal = information.diagonal();
  while (damping->lambda <= 1e10) {
    const Vector6d step = detail::solve_spd(information, gradient, 1.0 + damping->lambda);
    // The model's decrease 2 s.g - s.I.s, with I s = g - lambda diag(I) s
    // (the damped system solved): s.g + lambda sum I_ii s_i^2, no 6x6 product.
    const double predicted = step.dot(gradient) + damping->lambda * diagonal.dot(step.cwiseAbs2());
    // A step with an entry not finite has a predicted decrease not finite (the
    // diagonal of I and lambda are positive): one test in the common case, not six.
    if (!std::isfinite(predicted) && !step.allFinite()) {
      out.singular = true;
      break;
    }
    // A step the model does not predict to lower the cost is refused without
    // evaluating it.
    if (predicted > 0) {
      // Its reciprocal now, while the trial state is measured: the gain below
      // then waits for a multiplication, not for a division.
      const double inv_predicted = 1.0 / predicted;
      const Vector6d trial = x + step;
      next->trig = euler_trig_after(at.trig, step, trial);
      if (map.evaluate(trial, next) && next->cost <= at.cost) {
        const double decrease = at.cost - next->cost;
        if (decrease > 0) {  // a gain above zero
          out.step = step;
          out.accepted = true;
          // 2 gain - 1 and 1 - (2 gain - 1)^3, a multiply-add each.
          const double ratio = std::fma(decrease, 2 * inv_predicted, -1.0);
          damping->lambda *= std::max(1.0 / 3.0, std::fma(-ratio * ratio, ratio, 1.0));
          damping->growth = 2;
          break;
        }
      }
    }
    damping->lambda *= damping->growth;
    damping->growth *= 2;
  }
  return out;
}

// Where the updates stopped: the state, the system there (its projection and
// sines and cosines), the information matrix of the last update, how many
// updates, and why they stopped.
struct Updates {
  Vector6d x;
  const Linearisation* at_x = nullptr;
  Symmetric6 information;
  int iterations = 0;
  Termination termination = Termination::kMaxIterations;
};

// The measurement update (eqs. 25-28), relinearised about the current state
// until it stops moving, from the system `at` at the prior mean. Written in
// information form, which gives the same state and covariance as the gain
// form (K = P H^T (H P H^T + R)^-1) while inverting a 6x6 matrix instead of a
// 2N x 2N one:
//   P+ = (P^-1 + H^T R^-1 H)^-1,
//   x_{i+1} = x_i + P+ (H^T R^-1 (z - h(x_i)) - P^-1 (x_i - x_prior)).
// The update minimises the filter's MAP cost; a Gauss-Newton step that would
// raise it (a poor start, or the curved valley between the two planar poses)
// is damped Levenberg-Marquardt style instead of taken: the damped iterated
// EKF (Bell & Cathey 1993 view the IEKF as Gauss-Newton), same fixed point
// and posterior covariance.
inline Updates run_updates(const MapCost& map, const EkfOptions& options, Linearisation* at,
                           Linearisation* next) {
  Updates u;
  u.x = map.x_prior;
  u.at_x = at;
  u.information = map.prior_information;
  Damping damping;
  for (int it = 1; it <= options.max_iterations; ++it) {
    u.iterations = it;
    const Symmetric6& information = at->system.information;
    u.information = information;
    const Vector6d gradient = map.gradient(*at);
    const DampedStep d = damped_step(map, u.x, *at, information, gradient, &damping, next);
    if (d.singular) {
      u.termination = Termination::kNumericalFailure;
      return u;
    }
    if (!d.accepted || d.step.cwiseAbs().maxCoeff() <= options.state_tolerance) {
      // No step lowers the cost any more, or the step is negligible: the
      // minimum, to rounding.
      u.termination = Termination::kConverged;
      if (d.accepted) {
        u.x += d.step;
        u.at_x = next;
      }
      return u;
    }
    u.x += d.step;
    map.linearise(next);
    std::swap(at, next);
    u.at_x = at;
  }
  return u;
}

// run_updates built for each instruction set, with everything it calls but
// the measurement compiled into it.
VISION_INLINE_ALL Updates run_updates_baseline(const MapCost& map, const EkfOptions& options,
                                               Linearisation* at, Linearisation* next) {
  return run_updates(map, options, at, next);
}

#if defined(VISION_AVX2_FMA)
VISION_AVX2_FMA Updates run_updates_avx2_fma(const MapCost& map, const EkfOptions& options,
                                             Linearisation* at, Linearisation* next) {
  return run_updates(map, options, at, next);
}
#endif

Updates run_updates(EkfInstructionSet set, const MapCost& map, const EkfOptions& options,
                    Linearisation* at, Linearisation* next) {
#if defined(VISION_AVX2_FMA)
  if (set == EkfInstructionSet::kAvx2Fma) return run_updates_avx2_fma(map, options, at, next);
#endif
  (void)set;
  return run_updates_baseline(map, options, at, next);
}

// Converged or not, and why, once the iterations have stopped with the
// residual |r|^2 (pixels^2) at their state. Consistency gate: a state that
// explains the corners far worse than the measurement noise allows is a
// wrong local minimum, not a pose.
void settle_termination(const MapCost& map, double residual_squared, const EkfOptions& options,
                        Estimate* e) {
  if (e->termination == Termination::kConverged) {
    const double rms = std::sqrt(residual_squared / (2.0 * static_cast<double>(map.points.count)));
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

}  // namespace

Estimate iterated_ekf(const Correspondences& c, const Pose& prior, const Matrix6d& prior_covariance,
                      const EkfOptions& options) {
  const EkfInstructionSet set = detail::ekf_instruction_set(options.instruction_set);
  const MapCost map = map_cost(c, prior, prior_covariance, options, set);
  Linearisation systems[2];
  // The two systems' projected blocks: on the stack up to 16 points.
  constexpr size_t kStackBlocks = 4;
  const size_t blocks = map.points.blocks.size();
  detail::ProjectedBlock stack_blocks[2 * kStackBlocks];
  std::vector<detail::ProjectedBlock> heap_blocks(blocks > kStackBlocks ? 2 * blocks : 0);
  detail::ProjectedBlock* projected = blocks > kStackBlocks ? heap_blocks.data() : stack_blocks;
  systems[0].projection.blocks = projected;
  systems[1].projection.blocks = projected + blocks;
  systems[0].trig = euler_trig(map.x_prior);
  Estimate e;
  if (!map.evaluate(map.x_prior, &systems[0])) {
    e.termination = Termination::kBehindCamera;
    e.message = "the prior state puts an object point behind the camera";
    e.T_cam_target = pose_from_state(map.x_prior);
    e.covariance = inverse_spd(map.prior_information);
    return e;
  }
  map.linearise(&systems[0]);
  const Updates u = run_updates(set, map, options, &systems[0], &systems[1]);
  e.iterations = u.iterations;
  e.termination = u.termination;
  if (u.termination == Termination::kNumericalFailure)
    e.message = "the measurement update is singular";
  // The rotation from the sines and cosines the updates carried to u.x.
  e.T_cam_target = {u.at_x->projection.pose.rotation(), u.x.tail<3>()};
  e.covariance = inverse_spd(u.information);
  settle_termination(map, u.at_x->projection.residual_squared, options, &e);
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
