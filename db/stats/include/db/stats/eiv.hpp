// Errors-in-variables straight lines: both the bench read-back (x, true
// distance) and the solver's estimate (y) are uncertain, so ordinary least
// squares of y on x is biased towards a flatter slope (regression dilution).
//
//  - Deming regression: one ratio delta = var(error of y) / var(error of x)
//    for every point; closed form (Deming 1943; e.g. Cornbleet & Gochman,
//    Clin. Chem. 25 (1979) 432):
//        slope = (Syy - delta Sxx + sqrt((Syy - delta Sxx)^2 + 4 delta Sxy^2)) / (2 Sxy)
//    with centred sums Sxx, Syy, Sxy. delta -> infinity is OLS of y on x
//    (x exact), delta -> 0 the inverse regression x on y (slope Syy/Sxy),
//    delta = 1 orthogonal regression.
//  - York's method: a standard deviation in x and in y for every point (and
//    optionally their correlation), York, Evensen, Martinez, De Basabe
//    Delgado, "Unified equations for the slope, intercept, and standard
//    errors of the best straight line", Am. J. Phys. 72(3) 367-375 (2004),
//    the iterative algorithm summarised in their section III, with their
//    standard errors of slope and intercept.
#pragma once

#include <cstddef>
#include <vector>

namespace db::stats {

// A straight line y = slope * x + intercept fitted with errors in both
// variables. Units: slope [y]/[x]; intercept [y].
struct EivFit {
  double slope = 0.0;
  double intercept = 0.0;
  double slope_se = 0.0;
  double intercept_se = 0.0;
  double slope_intercept_cov = 0.0;
  std::size_t n = 0;
  // York only: sum of W_i (y_i - slope x_i - intercept)^2 / (n - 2), the
  // mean square weighted deviation; ~1 when the stated uncertainties explain
  // the scatter. Multiply the standard errors by its square root to scale
  // them to the observed scatter. 0 for Deming.
  double reduced_chi_squared = 0.0;
  int iterations = 0;     // York: slope updates done; Deming: 0
  bool converged = true;  // York: relative slope change fell below the tolerance
};

// Deming regression with error-variance ratio delta = var(y error) / var(x
// error) (> 0, finite).
// Standard errors by the delete-one jackknife, as in Linnet's
// method-comparison work (Stat. Med. 9 (1990) 1463), because it needs neither
// normal errors nor a large-sample formula:
//     se^2 = (n-1)/n * sum_i (theta_(i) - mean theta_(.))^2
// over the n leave-one-out fits. The leave-one-out sums are down-dated in
// O(1) each, so the whole fit is O(n). If leaving one point out makes Sxy
// vanish, that subset has no Deming slope and the standard errors are not
// finite.
// Preconditions: x.size() == y.size() >= 3, all finite, Sxy != 0 (zero
// covariance defines no Deming slope), delta > 0 and finite. Throws
// StatsError otherwise.
EivFit fit_deming(const std::vector<double>& x, const std::vector<double>& y, double delta);

// York's iteration: stops when |slope change| <= tolerance * |slope|, or
// after max_iterations (then converged = false).
struct YorkOptions {
  // Relative change of the slope that ends the iteration. 1e-13 is a few
  // hundred ulps: far below any statistical uncertainty, yet safely above the
  // rounding noise in which the iteration could cycle without settling.
  // Larger values stop earlier with a slope accurate to about the tolerance.
  double tolerance = 1e-13;
  // Upper bound on slope updates; York's iteration converges linearly, so a
  // few hundred suffice even when x and y errors are of similar size.
  int max_iterations = 500;
};

// York et al. (2004) best straight line with per-point standard deviations
// sigma_x (>= 0; 0 means x exact) and sigma_y (> 0), and optional per-point
// correlation r_xy of the x and y errors (empty: 0; else |r| <= 1). The
// standard errors are those of the stated uncertainties (York's sigma_a,
// sigma_b), not rescaled by reduced_chi_squared. With every sigma_x = 0 the
// result is weighted least squares of y on x with weights 1/sigma_y^2.
// Preconditions: equal sizes >= 3, finite values, x not all equal.
// Throws StatsError otherwise.
EivFit fit_york(const std::vector<double>& x, const std::vector<double>& y,
                const std::vector<double>& sigma_x, const std::vector<double>& sigma_y,
                const std::vector<double>& r_xy = {}, const YorkOptions& options = {});

}  // namespace db::stats
