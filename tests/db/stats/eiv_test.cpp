// Errors-in-variables lines: Deming against its closed form and its limits,
// York against a published worked example.
#include "db/stats/eiv.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "db/stats/error.hpp"
#include "db/stats/regression.hpp"

namespace {

using db::stats::EivFit;

// A spread of 12 points with scatter in both coordinates; slope ~0.9.
const std::vector<double> kX = {0.12, 0.19, 0.27, 0.33, 0.41, 0.48,
                                0.55, 0.63, 0.71, 0.78, 0.86, 0.95};
const std::vector<double> kY = {0.118, 0.183, 0.251, 0.312, 0.372, 0.449,
                                0.491, 0.577, 0.648, 0.699, 0.781, 0.848};

TEST(FitDeming, MatchesTheHandComputedClosedForm) {
  // x = {1,2,3,4}, y = {2,3,5,6}: means 2.5 and 4; deviations dx = {-1.5,
  // -0.5, 0.5, 1.5}, dy = {-2, -1, 1, 2}; Sxx = 5, Syy = 10, Sxy = 3 + 0.5 +
  // 0.5 + 3 = 7. With delta = 2: Syy - delta Sxx = 0, so
  // slope = (0 + sqrt(0 + 4 * 2 * 49)) / (2 * 7) = 14 sqrt(2) / 14 = sqrt(2),
  // intercept = 4 - 2.5 sqrt(2).
  const EivFit fit = db::stats::fit_deming({1, 2, 3, 4}, {2, 3, 5, 6}, 2.0);
  EXPECT_NEAR(fit.slope, std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(fit.intercept, 4.0 - 2.5 * std::sqrt(2.0), 4e-15);
}

TEST(FitDeming, LargeDeltaGivesOrdinaryLeastSquaresOfYOnX) {
  // The Deming slope departs from the OLS slope by O(1 / delta) relative
  // (residual variance over delta var x, ~1e-3 / 1e12 here), far below 1e-12.
  const EivFit deming = db::stats::fit_deming(kX, kY, 1e12);
  const db::stats::LineFit ols = db::stats::fit_line(kX, kY);
  EXPECT_NEAR(deming.slope, ols.slope, 1e-12 * std::abs(ols.slope));
  EXPECT_NEAR(deming.intercept, ols.intercept, 1e-12);
}

TEST(FitDeming, SmallDeltaGivesTheInverseRegressionOfXOnY) {
  // x = c y + d by OLS, solved for y: slope 1/c, intercept -d/c.
  const EivFit deming = db::stats::fit_deming(kX, kY, 1e-12);
  const db::stats::LineFit inverse = db::stats::fit_line(kY, kX);
  EXPECT_NEAR(deming.slope, 1.0 / inverse.slope, 1e-11);
  EXPECT_NEAR(deming.intercept, -inverse.intercept / inverse.slope, 1e-11);
}

TEST(FitDeming, SwappingXAndYWithTheInverseRatioInvertsTheLine) {
  // Deming treats x and y symmetrically once delta is inverted.
  const EivFit xy = db::stats::fit_deming(kX, kY, 3.0);
  const EivFit yx = db::stats::fit_deming(kY, kX, 1.0 / 3.0);
  EXPECT_NEAR(yx.slope, 1.0 / xy.slope, 1e-13);
}

TEST(FitDeming, JackknifeStandardErrorsEqualTheBruteForceLeaveOneOutFits) {
  // The O(n) down-dated jackknife against n independent refits of n-1 points.
  const double delta = 2.0;
  const EivFit fit = db::stats::fit_deming(kX, kY, delta);
  const std::size_t n = kX.size();
  std::vector<double> slopes, intercepts;
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<double> x, y;
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i) continue;
      x.push_back(kX[j]);
      y.push_back(kY[j]);
    }
    const EivFit one = db::stats::fit_deming(x, y, delta);
    slopes.push_back(one.slope);
    intercepts.push_back(one.intercept);
  }
  auto jackknife_se = [n](const std::vector<double>& v) {
    double m = 0;
    for (double e : v)
      m += e;
    m /= static_cast<double>(n);
    double s = 0;
    for (double e : v)
      s += (e - m) * (e - m);
    return std::sqrt(s * static_cast<double>(n - 1) / static_cast<double>(n));
  };
  EXPECT_NEAR(fit.slope_se, jackknife_se(slopes), 1e-10 * jackknife_se(slopes));
  EXPECT_NEAR(fit.intercept_se, jackknife_se(intercepts), 1e-10 * jackknife_se(intercepts));
  EXPECT_GT(fit.slope_se, 0.0);
}

TEST(FitDeming, RejectsANonPositiveRatio) {
  EXPECT_THROW(db::stats::fit_deming(kX, kY, 0.0), db::stats::StatsError);
}

// Pearson's (1901) data with York's (1966) weights omega = 1 / sigma^2, the
// worked example of York et al. 2004 (Am. J. Phys. 72, 367), whose solution
// they give as slope -0.4805 and intercept 5.4799. The 10-digit values and
// the standard errors below are the expectations of an independent
// implementation's test suite: R package bfsl 0.2.0 (York 2004 algorithm),
// tests/testthat/test-bfsl.R: intercept 5.479910224 +- 0.294970735, slope
// -0.480533407 +- 0.0579850090, reduced chi^2 1.483294149.
const std::vector<double> kPearsonX = {0.0, 0.9, 1.8, 2.6, 3.3, 4.4, 5.2, 6.1, 6.5, 7.4};
const std::vector<double> kPearsonY = {5.9, 5.4, 4.4, 4.6, 3.5, 3.7, 2.8, 2.8, 2.4, 1.5};
const std::vector<double> kYorkWx = {1000, 1000, 500, 800, 200, 80, 60, 20, 1.8, 1};
const std::vector<double> kYorkWy = {1, 1.8, 4, 8, 20, 20, 70, 70, 100, 500};

std::vector<double> sigmas(const std::vector<double>& weights) {
  std::vector<double> s;
  for (double w : weights)
    s.push_back(1.0 / std::sqrt(w));
  return s;
}

// bfsl's figures carry 10 significant digits (half a unit in the last is
// <= 2e-9 relative) and bfsl stops iterating at its own tolerance, so 2e-8
// relative is what agreement can mean here.
constexpr double kBfslRelative = 2e-8;

TEST(FitYork, ReproducesYork2004PearsonExampleSlopeAndIntercept) {
  const EivFit fit = db::stats::fit_york(kPearsonX, kPearsonY, sigmas(kYorkWx), sigmas(kYorkWy));
  EXPECT_TRUE(fit.converged);
  EXPECT_NEAR(fit.slope, -0.4805, 0.5e-4);  // York et al. 2004, 4 decimals
  EXPECT_NEAR(fit.intercept, 5.4799, 0.5e-4);
  EXPECT_NEAR(fit.slope, -0.480533407, kBfslRelative * 0.480533407);
  EXPECT_NEAR(fit.intercept, 5.479910224, kBfslRelative * 5.479910224);
}

TEST(FitYork, ReproducesThePearsonExampleStandardErrorsAndReducedChiSquared) {
  const EivFit fit = db::stats::fit_york(kPearsonX, kPearsonY, sigmas(kYorkWx), sigmas(kYorkWy));
  EXPECT_NEAR(fit.slope_se, 0.0579850090, kBfslRelative * 0.0579850090);
  EXPECT_NEAR(fit.intercept_se, 0.294970735, kBfslRelative * 0.294970735);
  EXPECT_NEAR(fit.reduced_chi_squared, 1.483294149, kBfslRelative * 1.483294149);
}

TEST(FitYork, ExactXGivesWeightedLeastSquaresOfYOnX) {
  // sigma_x = 0: W_i = 1/sigma_y^2 and beta_i = U_i, so York's slope is the
  // weighted LS slope and sigma_b^2 = 1/sum W U^2 its known-sigma variance.
  // The weighted fit is computed by a different route (QR of the whitened
  // design); both are exact up to rounding.
  const std::vector<double> zero(kPearsonX.size(), 0.0);
  const EivFit york = db::stats::fit_york(kPearsonX, kPearsonY, zero, sigmas(kYorkWy));
  const db::stats::LineFit wls =
      db::stats::fit_line_weighted(kPearsonX, kPearsonY, sigmas(kYorkWy));
  EXPECT_NEAR(york.slope, wls.slope, 1e-12);
  EXPECT_NEAR(york.intercept, wls.intercept, 1e-12);
  EXPECT_NEAR(york.slope_se, wls.slope_se, 1e-12);
  EXPECT_NEAR(york.intercept_se, wls.intercept_se, 1e-12);
  EXPECT_NEAR(york.reduced_chi_squared, wls.residual_variance, 1e-12);
}

TEST(FitYork, RejectsANonPositiveSigmaY) {
  std::vector<double> sy = sigmas(kYorkWy);
  sy[3] = 0.0;
  EXPECT_THROW(db::stats::fit_york(kPearsonX, kPearsonY, sigmas(kYorkWx), sy),
               db::stats::StatsError);
}

}  // namespace
