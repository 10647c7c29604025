#include "db/stats/compare.hpp"

#include <math.h>

#include <cmath>
#include <string>

#include "db/stats/error.hpp"

namespace db::stats {

namespace {

void require_k(const char* function, double k) {
  if (!(k > 0.0) || !std::isfinite(k)) {
    throw StatsError(std::string(function) + ": k = " + std::to_string(k) +
                     "; expected a finite number of standard errors > 0");
  }
}

Difference make(double difference, double se, double k) {
  Difference d;
  d.difference = difference;
  d.standard_error = se;
  if (se > 0.0) {
    d.z = difference / se;
  } else {
    d.z = difference == 0.0 ? 0.0
                            : std::copysign(std::numeric_limits<double>::infinity(), difference);
  }
  d.significant = std::abs(difference) > k * se;
  return d;
}

}  // namespace

Difference compare_means(const Summary& candidate, const Summary& baseline, double k) {
  constexpr const char* kName = "compare_means";
  require_k(kName, k);
  for (const Summary* s : {&candidate, &baseline}) {
    if (s->count < 2 || !std::isfinite(s->variance) || !std::isfinite(s->mean)) {
      throw StatsError(std::string(kName) + ": a sample of " + std::to_string(s->count) +
                       " values with variance " + std::to_string(s->variance) +
                       "; expected at least 2 values and a finite variance");
    }
  }
  const double v1 = candidate.variance / static_cast<double>(candidate.count);
  const double v2 = baseline.variance / static_cast<double>(baseline.count);
  Difference d = make(candidate.mean - baseline.mean, std::sqrt(v1 + v2), k);
  const double den = v1 * v1 / static_cast<double>(candidate.count - 1) +
                     v2 * v2 / static_cast<double>(baseline.count - 1);
  d.dof = den > 0.0 ? (v1 + v2) * (v1 + v2) / den : std::numeric_limits<double>::infinity();
  return d;
}

Difference compare_estimates(double candidate, double candidate_se, double baseline,
                             double baseline_se, double k) {
  constexpr const char* kName = "compare_estimates";
  require_k(kName, k);
  if (!std::isfinite(candidate) || !std::isfinite(baseline) || !(candidate_se >= 0.0) ||
      !(baseline_se >= 0.0) || !std::isfinite(candidate_se) || !std::isfinite(baseline_se)) {
    throw StatsError(std::string(kName) + ": estimates " + std::to_string(candidate) + " +- " +
                     std::to_string(candidate_se) + " and " + std::to_string(baseline) + " +- " +
                     std::to_string(baseline_se) +
                     "; expected finite values and standard errors >= 0");
  }
  return make(candidate - baseline, std::hypot(candidate_se, baseline_se), k);
}

Difference compare_slopes(const LineFit& candidate, const LineFit& baseline, double k) {
  return compare_estimates(candidate.slope, candidate.slope_se, baseline.slope, baseline.slope_se,
                           k);
}

namespace {

// Continued fraction of the regularized incomplete beta I_x(a, b), modified
// Lentz's method (Numerical Recipes 3rd ed. §6.4); converges fast for
// x < (a + 1) / (a + b + 2).
double beta_continued_fraction(double a, double b, double x) {
  const double tiny = 1e-300;
  double c = 1.0, d = 1.0 - (a + b) * x / (a + 1.0);
  if (std::abs(d) < tiny) d = tiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m <= 10000; ++m) {
    const double m2 = 2.0 * m;
    double aa = m * (b - m) * x / ((a - 1.0 + m2) * (a + m2));
    d = 1.0 + aa * d;
    if (std::abs(d) < tiny) d = tiny;
    c = 1.0 + aa / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    h *= d * c;
    aa = -(a + m) * (a + b + m) * x / ((a + m2) * (a + 1.0 + m2));
    d = 1.0 + aa * d;
    if (std::abs(d) < tiny) d = tiny;
    c = 1.0 + aa / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-15) break;
  }
  return h;
}

// log Γ(x), x > 0: lgamma_r (POSIX), because std::lgamma also writes the
// global signgam, a data race when the report studies solvers on two threads.
double log_gamma(double x) {
  int sign = 0;
  return lgamma_r(x, &sign);
}

double regularized_incomplete_beta(double a, double b, double x) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  const double front = std::exp(log_gamma(a + b) - log_gamma(a) - log_gamma(b) + a * std::log(x) +
                                b * std::log1p(-x));
  if (x < (a + 1.0) / (a + b + 2.0)) return front * beta_continued_fraction(a, b, x) / a;
  return 1.0 - front * beta_continued_fraction(b, a, 1.0 - x) / b;
}

}  // namespace

double two_sided_tail(double k, double dof) {
  if (!(k >= 0.0) || !std::isfinite(k) || !(dof > 0.0)) {
    throw StatsError("two_sided_tail: k = " + std::to_string(k) + ", dof = " + std::to_string(dof) +
                     "; expected k >= 0 finite and dof > 0");
  }
  if (std::isinf(dof)) return std::erfc(k / std::sqrt(2.0));
  return regularized_incomplete_beta(dof / 2.0, 0.5, dof / (dof + k * k));
}

double two_sided_threshold(double p, double dof) {
  if (!(p > 0.0 && p < 1.0) || !(dof > 0.0)) {
    throw StatsError("two_sided_threshold: p = " + std::to_string(p) +
                     ", dof = " + std::to_string(dof) + "; expected 0 < p < 1 and dof > 0");
  }
  // The tail falls from 1 at k = 0; grow the bracket until it is below p
  // (t with one degree of freedom needs k ~ 2 / (pi p) for small p).
  double lo = 0.0, hi = 1.0;
  while (two_sided_tail(hi, dof) > p)
    hi *= 2.0;
  while (hi - lo > 1e-12 * hi) {
    const double mid = 0.5 * (lo + hi);
    (two_sided_tail(mid, dof) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace db::stats
