// Least-squares straight lines for the distance regressions of the reports
// (paper Tables 4-5: estimated = a * true + b, asymptotic standard errors,
// RMS and variance of the residuals).
//
// Numerics: the data are centred on their means (computed with one
// correction pass) before any sum of products is formed, and residuals are
// formed from the data, never from sums of squares, so the NIST StRD linear
// datasets (Norris, NoInt1) are reproduced to ~1e-13 relative.
//
// Vocabulary, because the paper used gnuplot's `fit` whose printout it copied:
//   residual_variance = SSR / dof   gnuplot "variance of residuals (reduced chisquare)",
//                                   paper Table 5 "Variance of residuals"
//   residual_sd       = sqrt(SSR / dof)   gnuplot "rms of residuals (FIT_STDFIT)",
//                                   paper Table 5 "RMS of residuals", NIST
//                                   "residual standard deviation"
//   residual_rms      = sqrt(SSR / n)  the plain root mean square of the residuals
// (Table 5's RMS squared equals its variance: 0.0069^2 ~ 4.82e-5.)
#pragma once

#include <cstddef>
#include <vector>

namespace db::stats {

// A fitted line y = slope * x + intercept and its uncertainty. Units: slope in
// [y]/[x], intercept and residual figures in [y].
struct LineFit {
  double slope = 0.0;
  double intercept = 0.0;  // exactly 0 for a line through the origin
  // Asymptotic standard errors (square roots of the diagonal of the
  // covariance s^2 (X^T X)^-1), as gnuplot and NIST report them.
  double slope_se = 0.0;
  double intercept_se = 0.0;           // 0 for a line through the origin
  double slope_intercept_cov = 0.0;    // covariance of slope and intercept
  std::size_t n = 0;                   // number of points
  std::size_t dof = 0;                 // n - number of parameters
  double residual_sum_of_squares = 0;  // SSR = sum (y - fit)^2 (weighted: chi^2)
  double residual_variance = 0.0;      // SSR / dof
  double residual_sd = 0.0;            // sqrt(SSR / dof)
  double residual_rms = 0.0;           // sqrt(SSR / n)
  // Coefficient of determination 1 - SSR / SST. With an intercept SST is
  // centred, sum (y - mean y)^2; through the origin it is uncentred, sum y^2
  // (the convention of NIST NoInt1/NoInt2 and of R's lm without intercept).
  double r_squared = 0.0;
};

// Ordinary least squares y = a x + b.
// Preconditions: x.size() == y.size() >= 3 (one residual degree of freedom),
// all values finite, x not all equal. Throws StatsError otherwise.
LineFit fit_line(const std::vector<double>& x, const std::vector<double>& y);

// Ordinary least squares through the origin, y = a x (intercept fixed at 0).
// Preconditions: x.size() == y.size() >= 2, all finite, x not all zero.
// Throws StatsError otherwise.
LineFit fit_line_through_origin(const std::vector<double>& x, const std::vector<double>& y);

// Weighted least squares y = a x + b with known standard deviations sigma_y
// of each y (weights 1 / sigma_y^2). The standard errors are those of the
// stated uncertainties, sqrt(diag (X^T W X)^-1), not rescaled by the scatter;
// residual_sum_of_squares is chi^2 = sum ((y - fit) / sigma_y)^2 and
// residual_variance is the reduced chi^2 (multiply the standard errors by
// residual_sd to get the scatter-scaled ones). r_squared is the weighted
// centred R^2. Solved by Householder QR of the whitened design (Eigen).
// Preconditions: equal sizes >= 3, finite values, every sigma_y > 0, x not
// all equal. Throws StatsError otherwise.
LineFit fit_line_weighted(const std::vector<double>& x, const std::vector<double>& y,
                          const std::vector<double>& sigma_y);

}  // namespace db::stats
