#include "db/stats/eiv.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "check.hpp"

namespace db::stats {

namespace {

// Deming slope from centred sums. The quadratic Sxy b^2 - q b - delta Sxy = 0
// (q = Syy - delta Sxx) has roots whose product is -delta; when q < 0 the
// textbook form (q + D) / (2 Sxy) cancels catastrophically for large delta,
// so the other root's reciprocal, 2 delta Sxy / (D - q), is used there.
// Sxy = 0 (possible only in a leave-one-out subset) has no Deming slope.
double deming_slope(double sxx, double syy, double sxy, double delta) {
  if (sxy == 0.0) return std::numeric_limits<double>::quiet_NaN();
  const double q = syy - delta * sxx;
  const double d = std::sqrt(q * q + 4.0 * delta * sxy * sxy);
  return q >= 0.0 ? (q + d) / (2.0 * sxy) : 2.0 * delta * sxy / (d - q);
}

}  // namespace

EivFit fit_deming(const std::vector<double>& x, const std::vector<double>& y, double delta) {
  constexpr const char* kName = "fit_deming";
  detail::require_same_size(kName, x, y);
  detail::require_at_least(kName, x.size(), 3);
  detail::require_finite(kName, "x", x);
  detail::require_finite(kName, "y", y);
  if (!(delta > 0.0) || !std::isfinite(delta)) {
    throw StatsError(std::string(kName) + ": delta = " + std::to_string(delta) +
                     "; expected a finite error-variance ratio > 0");
  }
  const detail::CentredMoments moments = detail::centred_moments(x, y);
  const double mx = moments.mean_x, my = moments.mean_y;
  const double sxx = moments.sxx, syy = moments.syy, sxy = moments.sxy;
  if (sxy == 0.0) {
    throw StatsError(std::string(kName) +
                     ": the covariance of x and y is 0; expected correlated data");
  }
  EivFit fit;
  fit.n = x.size();
  fit.slope = deming_slope(sxx, syy, sxy, delta);
  fit.intercept = my - fit.slope * mx;

  // Jackknife: removing point i from n points with means (mx, my) changes the
  // centred sums by -n/(n-1) dx dy and the means by -d/(n-1).
  const double n = static_cast<double>(fit.n);
  const double shrink = n / (n - 1.0);
  std::vector<double> slopes(fit.n), intercepts(fit.n);
  double slope_sum = 0.0, intercept_sum = 0.0;
  for (std::size_t i = 0; i < fit.n; ++i) {
    const double dx = x[i] - mx, dy = y[i] - my;
    const double s =
        deming_slope(sxx - shrink * dx * dx, syy - shrink * dy * dy, sxy - shrink * dx * dy, delta);
    slopes[i] = s;
    intercepts[i] = (my - dy / (n - 1.0)) - s * (mx - dx / (n - 1.0));
    slope_sum += slopes[i];
    intercept_sum += intercepts[i];
  }
  const double slope_mean = slope_sum / n, intercept_mean = intercept_sum / n;
  double vs = 0.0, vi = 0.0, cv = 0.0;
  for (std::size_t i = 0; i < fit.n; ++i) {
    const double ds = slopes[i] - slope_mean, di = intercepts[i] - intercept_mean;
    vs += ds * ds;
    vi += di * di;
    cv += ds * di;
  }
  const double factor = (n - 1.0) / n;
  fit.slope_se = std::sqrt(factor * vs);
  fit.intercept_se = std::sqrt(factor * vi);
  fit.slope_intercept_cov = factor * cv;
  return fit;
}

namespace {

// The points of a York fit: values, standard deviations and the optional
// correlation of their x and y errors.
struct YorkPoints {
  const std::vector<double>& x;
  const std::vector<double>& y;
  const std::vector<double>& sigma_x;
  const std::vector<double>& sigma_y;
  const std::vector<double>& r_xy;  // empty: 0 for every point
  std::size_t size() const { return x.size(); }
  double r(std::size_t i) const { return r_xy.empty() ? 0.0 : r_xy[i]; }
};

// Equal sizes >= 3, finite values, sigma_x >= 0, sigma_y > 0, |r| <= 1.
void check_york_points(const char* name, const YorkPoints& p) {
  detail::require_same_size(name, p.x, p.y);
  detail::require_same_size(name, p.x, p.sigma_x);
  detail::require_same_size(name, p.x, p.sigma_y);
  if (!p.r_xy.empty()) detail::require_same_size(name, p.x, p.r_xy);
  detail::require_at_least(name, p.size(), 3);
  detail::require_finite(name, "x", p.x);
  detail::require_finite(name, "y", p.y);
  detail::require_finite(name, "sigma_x", p.sigma_x);
  detail::require_finite(name, "sigma_y", p.sigma_y);
  detail::require_finite(name, "r_xy", p.r_xy);
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!(p.sigma_x[i] >= 0.0) || !(p.sigma_y[i] > 0.0)) {
      throw StatsError(std::string(name) + ": point " + std::to_string(i) +
                       " has sigma_x = " + std::to_string(p.sigma_x[i]) + ", sigma_y = " +
                       std::to_string(p.sigma_y[i]) + "; expected sigma_x >= 0 and sigma_y > 0");
    }
    if (!p.r_xy.empty() && std::abs(p.r_xy[i]) > 1.0) {
      throw StatsError(std::string(name) + ": r_xy[" + std::to_string(i) +
                       "] = " + std::to_string(p.r_xy[i]) + "; expected a correlation in [-1, 1]");
    }
  }
}

// Step 1: the OLS slope as the starting value. Throws StatsError when every
// x is equal.
double ols_start_slope(const char* name, const YorkPoints& p) {
  const detail::CentredMoments m = detail::centred_moments(p.x, p.y);
  if (!(m.sxx > 0.0)) {
    throw StatsError(std::string(name) + ": every x equals " + std::to_string(m.mean_x) +
                     "; expected at least two distinct x values");
  }
  return m.sxy / m.sxx;
}

// Steps 2-5 at one slope: the weights W_i, the weighted centroid
// (xbar, ybar) and beta_i.
struct YorkWeights {
  std::vector<double> w, beta;
  double xbar = 0.0, ybar = 0.0, wsum = 0.0;
  explicit YorkWeights(std::size_t n) : w(n), beta(n) {}
};

// York writes steps 2-5 with weights omega = 1/sigma^2 and
// alpha = sqrt(omega_X omega_Y); multiplying through by the variances gives
// the same quantities without dividing by a zero sigma_x:
//   W = 1 / (sigma_y^2 + b^2 sigma_x^2 - 2 b r sigma_x sigma_y),
//   beta = W (U sigma_y^2 + b V sigma_x^2 - (b U + V) r sigma_x sigma_y).
void weights_at(double b, const YorkPoints& p, YorkWeights& out) {
  out.wsum = 0.0;
  double swx = 0.0, swy = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double sx = p.sigma_x[i], sy = p.sigma_y[i];
    out.w[i] = 1.0 / (sy * sy + b * b * sx * sx - 2.0 * b * p.r(i) * sx * sy);
    out.wsum += out.w[i];
    swx += out.w[i] * p.x[i];
    swy += out.w[i] * p.y[i];
  }
  out.xbar = swx / out.wsum;
  out.ybar = swy / out.wsum;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double sx = p.sigma_x[i], sy = p.sigma_y[i];
    const double u = p.x[i] - out.xbar, v = p.y[i] - out.ybar;
    out.beta[i] = out.w[i] * (u * sy * sy + b * v * sx * sx - (b * u + v) * p.r(i) * sx * sy);
  }
}

// Steps 2-7: iterates b = sum W beta V / sum W beta U until the relative
// change is within the tolerance or max_iterations updates were made; sets
// fit.iterations and fit.converged and returns the last slope.
double iterate_slope(double b, const YorkPoints& p, const YorkOptions& options,
                     YorkWeights& weights, EivFit& fit) {
  fit.converged = false;
  for (int it = 0; it < options.max_iterations; ++it) {
    weights_at(b, p, weights);
    double num = 0.0, den = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      num += weights.w[i] * weights.beta[i] * (p.y[i] - weights.ybar);
      den += weights.w[i] * weights.beta[i] * (p.x[i] - weights.xbar);
    }
    const double next = num / den;
    fit.iterations = it + 1;
    const bool done = std::abs(next - b) <= options.tolerance * std::abs(next);
    b = next;
    if (done) {
      fit.converged = true;
      break;
    }
  }
  return b;
}

// Steps 8-10 at the final slope b: intercept through the weighted centroid,
// adjusted x_i = Xbar + beta_i, and York's sigma_b^2 = 1 / sum W u^2,
// sigma_a^2 = 1 / sum W + xbar_adj^2 sigma_b^2, cov(a, b) = -xbar_adj sigma_b^2;
// and the reduced chi^2.
void line_and_errors(double b, const YorkPoints& p, YorkWeights& weights, EivFit& fit) {
  weights_at(b, p, weights);
  const std::vector<double>& w = weights.w;
  fit.slope = b;
  fit.intercept = weights.ybar - b * weights.xbar;
  double swadj = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i)
    swadj += w[i] * (weights.xbar + weights.beta[i]);
  const double xadj_bar = swadj / weights.wsum;
  double swu2 = 0.0, chi2 = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double u = weights.xbar + weights.beta[i] - xadj_bar;
    swu2 += w[i] * u * u;
    const double res = p.y[i] - b * p.x[i] - fit.intercept;
    chi2 += w[i] * res * res;
  }
  const double var_b = 1.0 / swu2;
  fit.slope_se = std::sqrt(var_b);
  fit.intercept_se = std::sqrt(1.0 / weights.wsum + xadj_bar * xadj_bar * var_b);
  fit.slope_intercept_cov = -xadj_bar * var_b;
  fit.reduced_chi_squared = chi2 / static_cast<double>(p.size() - 2);
}

}  // namespace

EivFit fit_york(const std::vector<double>& x, const std::vector<double>& y,
                const std::vector<double>& sigma_x, const std::vector<double>& sigma_y,
                const std::vector<double>& r_xy, const YorkOptions& options) {
  constexpr const char* kName = "fit_york";
  const YorkPoints points{x, y, sigma_x, sigma_y, r_xy};
  check_york_points(kName, points);
  const double start = ols_start_slope(kName, points);
  EivFit fit;
  fit.n = points.size();
  YorkWeights weights(points.size());
  const double slope = iterate_slope(start, points, options, weights, fit);
  line_and_errors(slope, points, weights, fit);
  return fit;
}

}  // namespace db::stats
