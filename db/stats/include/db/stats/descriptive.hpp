// Descriptive statistics for the report tables: mean, unbiased variance and
// standard deviation (paper Tables 2, 3, 6), percentiles, and the
// equal-width classes of distances (paper Fig. 11: ten classes over
// [0.10, 1.00] m).
#pragma once

#include <cstddef>
#include <limits>
#include <optional>
#include <vector>

namespace db::stats {

// Count, mean, unbiased variance (divisor n - 1), standard deviation, range.
// variance and sd are quiet NaN when count < 2 (undefined, not zero); mean,
// min and max are NaN when count == 0. Units: those of the values (variance
// in units squared).
struct Summary {
  std::size_t count = 0;
  double mean = std::numeric_limits<double>::quiet_NaN();
  double variance = std::numeric_limits<double>::quiet_NaN();
  double sd = std::numeric_limits<double>::quiet_NaN();
  double min = std::numeric_limits<double>::quiet_NaN();
  double max = std::numeric_limits<double>::quiet_NaN();
};

// Two-pass summary (mean with a correction pass, then the centred sum of
// squares), accurate even when the mean is large against the spread.
// Preconditions: every value finite; throws StatsError otherwise. An empty
// input gives count 0 and NaN figures.
Summary summarize(const std::vector<double>& values);

// Streaming summary by Welford's update (Welford, Technometrics 4 (1962)
// 419), for values read row by row from the database without holding them.
// add() throws StatsError on a non-finite value.
class RunningSummary {
 public:
  // Adds one value (units of the values). Throws StatsError naming the value
  // and how many came before if it is not finite; the summary is unchanged.
  void add(double value);
  // The Summary of the values added so far (as summarize, to rounding).
  Summary summary() const;

 private:
  std::size_t count_ = 0;
  double mean_ = 0.0;
  double m2_ = 0.0;  // sum of squared deviations from the running mean
  double min_ = 0.0;
  double max_ = 0.0;
};

// Quantile q in [0, 1] by linear interpolation between order statistics:
// h = (n - 1) q, result x[floor h] + (h - floor h) (x[floor h + 1] - x[floor h])
// on the sorted values; type 7 of Hyndman & Fan, "Sample quantiles in
// statistical packages", Am. Stat. 50 (1996) 361, the default of R and numpy.
// q = 0.5 is the median; quantile(v, 0.95) the 95th percentile.
// Preconditions: values non-empty and finite, 0 <= q <= 1; throws StatsError.
double quantile(std::vector<double> values, double q);

// Several quantiles of the same values with one sort (same definition), in
// the order of qs. Preconditions as quantile's, for every q; throws
// StatsError.
std::vector<double> quantiles(std::vector<double> values, const std::vector<double>& qs);

// N equal-width classes over [lower, upper], e.g. the paper's ten distance
// classes over [0.10, 1.00] m. Edge rule: class i is [edge(i), edge(i+1)),
// so a value on an inner edge belongs to the upper class, and the last class
// is closed, [edge(N-1), upper], so `upper` itself is in class N-1. Values
// within 1e-12 of the range width of an edge count as on it: a distance
// computed by another route (0.10 + 4 * 0.09 is 0.45999999999999996, the
// literal 0.46 is not) must not change class on a rounding error, and 1e-12
// of a 0.9 m range is 0.9 pm, far below any bench resolution.
class EqualWidthBins {
 public:
  // Preconditions: lower < upper, both finite, count >= 1; throws StatsError.
  EqualWidthBins(double lower, double upper, std::size_t count);

  std::size_t count() const { return count_; }
  double lower() const { return lower_; }
  double upper() const { return upper_; }
  // Edge i in [0, count]: lower + i (upper - lower) / count; edge(count) ==
  // upper (as is any i > count).
  double edge(std::size_t i) const;
  // Midpoint of class i (i < count).
  double centre(std::size_t i) const { return 0.5 * (edge(i) + edge(i + 1)); }
  // The class of value, or nullopt when it is outside [lower, upper] or NaN.
  std::optional<std::size_t> index_of(double value) const;

 private:
  double lower_;
  double upper_;
  std::size_t count_;
  double tolerance_;
};

}  // namespace db::stats
