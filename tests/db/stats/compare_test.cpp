// Run comparison: differences flagged only beyond k standard errors.
#include "db/stats/compare.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "db/stats/error.hpp"

namespace {

using db::stats::Difference;
using db::stats::Summary;

Summary sample(std::size_t n, double mean, double sd) {
  Summary s;
  s.count = n;
  s.mean = mean;
  s.variance = sd * sd;
  s.sd = sd;
  return s;
}

TEST(CompareMeans, GivesWelchStandardErrorAndDegreesOfFreedom) {
  // n = 100 each, sd 0.2: se^2 = 0.04/100 + 0.04/100 = 8e-4, se = 0.028284;
  // dof = (8e-4)^2 / (2 (4e-4)^2 / 99) = 198. Difference 0.1 -> z = 3.5355.
  const Difference d = db::stats::compare_means(sample(100, 1.1, 0.2), sample(100, 1.0, 0.2));
  EXPECT_NEAR(d.difference, 0.1, 1e-15);
  EXPECT_NEAR(d.standard_error, std::sqrt(8e-4), 1e-15);
  EXPECT_NEAR(d.dof, 198.0, 1e-9);
  EXPECT_NEAR(d.z, 0.1 / std::sqrt(8e-4), 1e-12);
}

TEST(CompareMeans, FlagsADifferenceBeyondKStandardErrorsOnly) {
  // z = 3.54: significant at k = 3, not at k = 4.
  const Summary a = sample(100, 1.1, 0.2), b = sample(100, 1.0, 0.2);
  EXPECT_TRUE(db::stats::compare_means(a, b, 3.0).significant);
  EXPECT_FALSE(db::stats::compare_means(a, b, 4.0).significant);
}

TEST(CompareMeans, WeighsUnequalSamplesAsWelch) {
  // n1 = 10, s1 = 3 -> v1 = 0.9; n2 = 40, s2 = 1 -> v2 = 0.025; se = sqrt(0.925);
  // dof = 0.925^2 / (0.81/9 + 0.000625/39) = 0.855625 / 0.09001603 = 9.50526.
  // Difference 2.5 is 2.60 se: flagged at k = 2.5, not at k = 3 (a pooled
  // variance would call it 4.5 se).
  const Summary a = sample(10, 12.5, 3.0), b = sample(40, 10.0, 1.0);
  const Difference d = db::stats::compare_means(a, b, 3.0);
  EXPECT_NEAR(d.standard_error, std::sqrt(0.925), 1e-15);
  EXPECT_NEAR(d.dof, 0.855625 / (0.81 / 9.0 + 0.000625 / 39.0), 1e-12);
  EXPECT_NEAR(d.dof, 9.50526, 1e-5);
  EXPECT_FALSE(d.significant);
  EXPECT_TRUE(db::stats::compare_means(a, b, 2.5).significant);
}

TEST(CompareMeans, FlagsADecreaseWithItsSign) {
  const Difference d = db::stats::compare_means(sample(50, 0.5, 0.1), sample(50, 0.6, 0.1));
  EXPECT_TRUE(d.significant);
  EXPECT_LT(d.difference, 0.0);
  EXPECT_LT(d.z, 0.0);
}

TEST(CompareMeans, RejectsASampleOfOneValue) {
  EXPECT_THROW(db::stats::compare_means(sample(1, 1.0, 0.0), sample(10, 1.0, 0.1)),
               db::stats::StatsError);
}

TEST(CompareSlopes, CombinesTheTwoStandardErrorsInQuadrature) {
  // Paper Table 4 figures as two runs: hybrid OI a = 1.0084 +- 0.0004 against
  // analytic a = 1.0081 +- 0.0009: se = sqrt(0.0004^2 + 0.0009^2) = 9.849e-4,
  // difference 3e-4 = 0.30 se, not significant.
  db::stats::LineFit oi, analytic;
  oi.slope = 1.0084;
  oi.slope_se = 0.0004;
  analytic.slope = 1.0081;
  analytic.slope_se = 0.0009;
  const Difference d = db::stats::compare_slopes(oi, analytic);
  EXPECT_NEAR(d.standard_error, std::sqrt(0.0004 * 0.0004 + 0.0009 * 0.0009), 1e-18);
  EXPECT_NEAR(d.difference, 3e-4, 1e-15);
  EXPECT_FALSE(d.significant);
  EXPECT_TRUE(std::isinf(d.dof));
}

TEST(CompareEstimates, FlagsTheEkfSlopeAgainstTheHybridEkf) {
  // Paper Table 4: EKF a = 2.6034 +- 0.2849 against hybrid EKF 1.0071 +-
  // 0.0003: 1.5963 / 0.2849 = 5.6 se, significant at k = 3.
  const Difference d = db::stats::compare_estimates(2.6034, 0.2849, 1.0071, 0.0003);
  EXPECT_TRUE(d.significant);
  EXPECT_GT(d.difference, 0.0);
  EXPECT_NEAR(d.z, 1.5963 / std::hypot(0.2849, 0.0003), 1e-12);
}

TEST(CompareEstimates, RejectsANegativeStandardError) {
  EXPECT_THROW(db::stats::compare_estimates(1.0, -0.1, 1.0, 0.1), db::stats::StatsError);
}

}  // namespace

// Student's t two-sided tails and thresholds. Closed forms where the
// distribution has one (1 and 2 degrees of freedom: Cauchy, and
// 1 - k / sqrt(k^2 + 2)); critical values of the NIST/SEMATECH e-Handbook's
// t table (§1.3.6.7.2, three decimals, hence 5e-4) elsewhere.
TEST(StudentT, TwoSidedTailMatchesTheClosedForms) {
  const double pi = 3.14159265358979323846;
  for (double k : {0.1, 1.0, 3.0, 30.0}) {
    EXPECT_NEAR(db::stats::two_sided_tail(k, 1.0), 1.0 - 2.0 / pi * std::atan(k), 1e-13) << k;
    EXPECT_NEAR(db::stats::two_sided_tail(k, 2.0), 1.0 - k / std::sqrt(k * k + 2.0), 1e-13) << k;
    EXPECT_NEAR(db::stats::two_sided_tail(k, std::numeric_limits<double>::infinity()),
                std::erfc(k / std::sqrt(2.0)), 1e-15)
        << k;
  }
  EXPECT_EQ(db::stats::two_sided_tail(0.0, 7.0), 1.0);
  // Far out in dof the t tail approaches the normal one.
  EXPECT_NEAR(db::stats::two_sided_tail(3.0, 1e7), std::erfc(3.0 / std::sqrt(2.0)), 1e-8);
}

TEST(StudentT, ThresholdsMatchTheTable) {
  EXPECT_NEAR(db::stats::two_sided_threshold(0.05, 1), 12.706, 5e-4);
  EXPECT_NEAR(db::stats::two_sided_threshold(0.05, 10), 2.228, 5e-4);
  EXPECT_NEAR(db::stats::two_sided_threshold(0.01, 5), 4.032, 5e-4);
  EXPECT_NEAR(db::stats::two_sided_threshold(0.01, 30), 2.750, 5e-4);
  EXPECT_NEAR(db::stats::two_sided_threshold(0.05, std::numeric_limits<double>::infinity()), 1.960,
              5e-4);
  // Inverse of the tail to its bisection tolerance.
  const double k = db::stats::two_sided_threshold(0.0027, 4);
  EXPECT_NEAR(db::stats::two_sided_tail(k, 4), 0.0027, 1e-12);
  EXPECT_THROW(db::stats::two_sided_threshold(0.0, 4), db::stats::StatsError);
  EXPECT_THROW(db::stats::two_sided_threshold(0.5, 0), db::stats::StatsError);
}
