// Descriptive statistics, quantiles and distance classes on hand-checked cases.
#include "db/stats/descriptive.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "db/stats/error.hpp"

namespace {

using db::stats::EqualWidthBins;
using db::stats::Summary;

TEST(Summarize, GivesMeanUnbiasedVarianceAndSdOfAHandCheckedSet) {
  // {2,4,4,4,5,5,7,9}: sum 40, mean 5; squared deviations 9,1,1,1,0,0,4,16 =
  // 32; unbiased variance 32 / 7.
  const Summary s = db::stats::summarize({2, 4, 4, 4, 5, 5, 7, 9});
  EXPECT_EQ(s.count, 8u);
  EXPECT_DOUBLE_EQ(s.mean, 5.0);
  EXPECT_DOUBLE_EQ(s.variance, 32.0 / 7.0);
  EXPECT_DOUBLE_EQ(s.sd, std::sqrt(32.0 / 7.0));
  EXPECT_EQ(s.min, 2.0);
  EXPECT_EQ(s.max, 9.0);
}

TEST(Summarize, StaysExactWhenTheMeanIsHugeAgainstTheSpread) {
  // 1e9 + {4, 7, 13, 16}: mean 1e9 + 10, deviations -6,-3,3,6, variance
  // 90 / 3 = 30. The one-pass formula (sum x^2 - n mean^2) / (n-1) loses all
  // digits here; every value and the mean are exact doubles, so both the
  // two-pass and Welford's update give 30 to rounding.
  const std::vector<double> v = {1e9 + 4, 1e9 + 7, 1e9 + 13, 1e9 + 16};
  EXPECT_NEAR(db::stats::summarize(v).variance, 30.0, 1e-9);
  db::stats::RunningSummary running;
  for (double x : v)
    running.add(x);
  EXPECT_NEAR(running.summary().variance, 30.0, 1e-6);
  EXPECT_DOUBLE_EQ(running.summary().mean, 1e9 + 10);
}

TEST(RunningSummary, AgreesWithTheTwoPassSummary) {
  const std::vector<double> v = {0.31, -1.2, 4.4, 2.25, 0.0, 7.5, -3.125};
  db::stats::RunningSummary running;
  for (double x : v)
    running.add(x);
  const Summary a = running.summary(), b = db::stats::summarize(v);
  EXPECT_EQ(a.count, b.count);
  EXPECT_NEAR(a.mean, b.mean, 1e-15);
  EXPECT_NEAR(a.variance, b.variance, 1e-14);
  EXPECT_EQ(a.min, b.min);
  EXPECT_EQ(a.max, b.max);
}

TEST(Summarize, LeavesTheVarianceUndefinedForOneValue) {
  const Summary s = db::stats::summarize({3.5});
  EXPECT_EQ(s.mean, 3.5);
  EXPECT_TRUE(std::isnan(s.variance));
  EXPECT_TRUE(std::isnan(s.sd));
}

TEST(Quantile, InterpolatesBetweenOrderStatisticsAsHyndmanFanType7) {
  // {1,2,3,4} (given unsorted): h = 3 q. q = 0.25: h = 0.75 -> 1 + 0.75 = 1.75;
  // q = 0.5: h = 1.5 -> 2.5; q = 0.9: h = 2.7 -> 3.7; q = 0 and 1: min, max.
  // (numpy.percentile([1,2,3,4], [25,50,90]) gives the same.)
  const std::vector<double> v = {4, 1, 3, 2};
  EXPECT_DOUBLE_EQ(db::stats::quantile(v, 0.25), 1.75);
  EXPECT_DOUBLE_EQ(db::stats::quantile(v, 0.5), 2.5);
  EXPECT_DOUBLE_EQ(db::stats::quantile(v, 0.9), 3.7);
  EXPECT_EQ(db::stats::quantile(v, 0.0), 1.0);
  EXPECT_EQ(db::stats::quantile(v, 1.0), 4.0);
}

TEST(Quantile, GivesSeveralQuantilesFromOneSort) {
  // {10, 20, 30, 40, 50}: h = 4 q; q = 0.1 -> 10 + 0.4 * 10 = 14; 0.5 -> 30.
  const std::vector<double> q = db::stats::quantiles({50, 10, 40, 20, 30}, {0.1, 0.5, 1.0});
  ASSERT_EQ(q.size(), 3u);
  EXPECT_DOUBLE_EQ(q[0], 14.0);
  EXPECT_DOUBLE_EQ(q[1], 30.0);
  EXPECT_DOUBLE_EQ(q[2], 50.0);
}

TEST(Quantile, RejectsAProbabilityOutsideZeroToOne) {
  EXPECT_THROW(db::stats::quantile({1, 2}, 1.5), db::stats::StatsError);
}

TEST(Quantile, RejectsAnEmptyInput) {
  EXPECT_THROW(db::stats::quantile({}, 0.5), db::stats::StatsError);
}

// The paper's ten distance classes: [0.10, 1.00] m, width 0.09 m.
const EqualWidthBins kPaperClasses(0.10, 1.00, 10);

TEST(EqualWidthBins, PutsAValueOnAnInnerEdgeInTheUpperClass) {
  const std::vector<double> inner = {0.19, 0.28, 0.37, 0.46, 0.55, 0.64, 0.73, 0.82, 0.91};
  for (std::size_t i = 0; i < inner.size(); ++i) {
    EXPECT_EQ(kPaperClasses.index_of(inner[i]), i + 1) << inner[i];
  }
}

TEST(EqualWidthBins, TreatsAValueARoundingErrorBelowAnEdgeAsOnIt) {
  // One ulp below the edge 0.55 is a rounding error (tolerance 1e-12 x 0.9 m);
  // 1e-9 m below it is a real value of the lower class.
  EXPECT_EQ(kPaperClasses.index_of(std::nextafter(0.55, 0.0)), 5u);
  EXPECT_EQ(kPaperClasses.index_of(0.10 + 4 * 0.09), 4u);
  EXPECT_EQ(kPaperClasses.index_of(0.55 - 1e-9), 4u);
}

TEST(EqualWidthBins, PutsTheBottomEdgeInTheFirstAndTheTopEdgeInTheLastClass) {
  EXPECT_EQ(kPaperClasses.index_of(0.10), 0u);
  EXPECT_EQ(kPaperClasses.index_of(1.00), 9u);
}

TEST(EqualWidthBins, PutsValuesJustBelowAnEdgeInTheLowerClass) {
  EXPECT_EQ(kPaperClasses.index_of(0.1899), 0u);
  EXPECT_EQ(kPaperClasses.index_of(0.5499), 4u);
  EXPECT_EQ(kPaperClasses.index_of(0.9999), 9u);
}

TEST(EqualWidthBins, LeavesValuesOutsideTheRangeUnclassified) {
  EXPECT_FALSE(kPaperClasses.index_of(0.0999).has_value());
  EXPECT_FALSE(kPaperClasses.index_of(1.0001).has_value());
  EXPECT_FALSE(kPaperClasses.index_of(std::nan("")).has_value());
}

TEST(EqualWidthBins, ReportsEdgesAndCentres) {
  EXPECT_DOUBLE_EQ(kPaperClasses.edge(0), 0.10);
  EXPECT_DOUBLE_EQ(kPaperClasses.edge(1), 0.19);
  EXPECT_EQ(kPaperClasses.edge(10), 1.00);
  EXPECT_DOUBLE_EQ(kPaperClasses.centre(0), 0.145);
}

TEST(EqualWidthBins, RejectsAnEmptyRange) {
  EXPECT_THROW(EqualWidthBins(1.0, 1.0, 10), db::stats::StatsError);
}

}  // namespace
