#include "db/stats/regression.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <string>

#include "check.hpp"

namespace db::stats {

namespace {

void fill_residual_figures(LineFit& fit, double ssr, double sst) {
  fit.residual_sum_of_squares = ssr;
  fit.residual_variance = ssr / static_cast<double>(fit.dof);
  fit.residual_sd = std::sqrt(fit.residual_variance);
  fit.residual_rms = std::sqrt(ssr / static_cast<double>(fit.n));
  fit.r_squared = sst > 0.0 ? 1.0 - ssr / sst : 0.0;
}

}  // namespace

LineFit fit_line(const std::vector<double>& x, const std::vector<double>& y) {
  constexpr const char* kName = "fit_line";
  detail::require_same_size(kName, x, y);
  detail::require_at_least(kName, x.size(), 3);
  detail::require_finite(kName, "x", x);
  detail::require_finite(kName, "y", y);

  const detail::CentredMoments moments = detail::centred_moments(x, y);
  const double mx = moments.mean_x, my = moments.mean_y;
  const double sxx = moments.sxx, syy = moments.syy, sxy = moments.sxy;
  if (!(sxx > 0.0)) {
    throw StatsError(std::string(kName) + ": every x equals " + std::to_string(mx) +
                     "; expected at least two distinct x values");
  }

  LineFit fit;
  fit.n = x.size();
  fit.dof = fit.n - 2;
  fit.slope = sxy / sxx;
  fit.intercept = my - fit.slope * mx;
  // Residuals from the centred data: r = dy - a dx, which equals
  // y - (a x + b) exactly in real arithmetic and avoids the cancellation of
  // SSR = Syy - a Sxy.
  double ssr = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double r = (y[i] - my) - fit.slope * (x[i] - mx);
    ssr += r * r;
  }
  fill_residual_figures(fit, ssr, syy);
  const double s2 = fit.residual_variance;
  const double n = static_cast<double>(fit.n);
  // Covariance of (a, b) for the centred design: var a = s^2/Sxx,
  // var b = s^2 (1/n + mx^2/Sxx), cov = -mx s^2/Sxx.
  fit.slope_se = std::sqrt(s2 / sxx);
  fit.intercept_se = std::sqrt(s2 * (1.0 / n + mx * mx / sxx));
  fit.slope_intercept_cov = -mx * s2 / sxx;
  return fit;
}

LineFit fit_line_through_origin(const std::vector<double>& x, const std::vector<double>& y) {
  constexpr const char* kName = "fit_line_through_origin";
  detail::require_same_size(kName, x, y);
  detail::require_at_least(kName, x.size(), 2);
  detail::require_finite(kName, "x", x);
  detail::require_finite(kName, "y", y);

  double sxx = 0.0, sxy = 0.0, syy = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxx += x[i] * x[i];
    sxy += x[i] * y[i];
    syy += y[i] * y[i];
  }
  if (!(sxx > 0.0)) {
    throw StatsError(std::string(kName) + ": every x is 0; expected at least one non-zero x");
  }
  LineFit fit;
  fit.n = x.size();
  fit.dof = fit.n - 1;
  fit.slope = sxy / sxx;
  double ssr = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double r = y[i] - fit.slope * x[i];
    ssr += r * r;
  }
  fill_residual_figures(fit, ssr, syy);
  fit.slope_se = std::sqrt(fit.residual_variance / sxx);
  return fit;
}

LineFit fit_line_weighted(const std::vector<double>& x, const std::vector<double>& y,
                          const std::vector<double>& sigma_y) {
  constexpr const char* kName = "fit_line_weighted";
  detail::require_same_size(kName, x, y);
  detail::require_same_size(kName, x, sigma_y);
  detail::require_at_least(kName, x.size(), 3);
  detail::require_finite(kName, "x", x);
  detail::require_finite(kName, "y", y);
  detail::require_finite(kName, "sigma_y", sigma_y);
  for (std::size_t i = 0; i < sigma_y.size(); ++i) {
    if (!(sigma_y[i] > 0.0)) {
      throw StatsError(std::string(kName) + ": sigma_y[" + std::to_string(i) +
                       "] = " + std::to_string(sigma_y[i]) + "; expected > 0");
    }
  }
  const Eigen::Index n = static_cast<Eigen::Index>(x.size());
  // Centre x on its plain mean so the two columns of the design are well
  // conditioned; the intercept is shifted back below.
  const double mx = detail::accurate_mean(x);
  Eigen::MatrixXd a(n, 2);
  Eigen::VectorXd b(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double w = 1.0 / sigma_y[static_cast<std::size_t>(i)];
    a(i, 0) = w * (x[static_cast<std::size_t>(i)] - mx);
    a(i, 1) = w;
    b(i) = w * y[static_cast<std::size_t>(i)];
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  if (qr.rank() < 2) {
    throw StatsError(std::string(kName) + ": every x equals " + std::to_string(mx) +
                     "; expected at least two distinct x values");
  }
  const Eigen::Vector2d p = qr.solve(b);
  // (A^T A)^-1 = P R^-1 R^-T P^T from the QR factors, without forming A^T A.
  const Eigen::Matrix2d r = qr.matrixR().topLeftCorner(2, 2).triangularView<Eigen::Upper>();
  const Eigen::Matrix2d r_inv = r.inverse();
  const Eigen::Matrix2d perm = qr.colsPermutation();
  const Eigen::Matrix2d cov_c = perm * (r_inv * r_inv.transpose()) * perm.transpose();

  LineFit fit;
  fit.n = x.size();
  fit.dof = fit.n - 2;
  fit.slope = p(0);
  // Uncentre: y = a (x - mx) + c  =>  b = c - a mx.
  fit.intercept = p(1) - p(0) * mx;
  fit.slope_se = std::sqrt(cov_c(0, 0));
  const double var_b = cov_c(1, 1) - 2.0 * mx * cov_c(0, 1) + mx * mx * cov_c(0, 0);
  fit.intercept_se = std::sqrt(var_b);
  fit.slope_intercept_cov = cov_c(0, 1) - mx * cov_c(0, 0);

  const Eigen::VectorXd residual = b - a * p;
  double sw = 0.0, swy = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double w = 1.0 / (sigma_y[i] * sigma_y[i]);
    sw += w;
    swy += w * y[i];
  }
  const double ybar_w = swy / sw;
  double sst = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double d = (y[i] - ybar_w) / sigma_y[i];
    sst += d * d;
  }
  fill_residual_figures(fit, residual.squaredNorm(), sst);
  return fit;
}

}  // namespace db::stats
