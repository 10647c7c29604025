#include "db/stats/descriptive.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "check.hpp"

namespace db::stats {

Summary summarize(const std::vector<double>& values) {
  detail::require_finite("summarize", "values", values);
  Summary s;
  s.count = values.size();
  if (s.count == 0) return s;
  s.mean = detail::accurate_mean(values);
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  s.min = *lo;
  s.max = *hi;
  if (s.count < 2) return s;
  double ss = 0.0;
  for (double v : values)
    ss += (v - s.mean) * (v - s.mean);
  s.variance = ss / static_cast<double>(s.count - 1);
  s.sd = std::sqrt(s.variance);
  return s;
}

void RunningSummary::add(double value) {
  if (!std::isfinite(value)) {
    throw StatsError("RunningSummary::add: value " + std::to_string(value) + " after " +
                     std::to_string(count_) + " values; expected a finite number");
  }
  ++count_;
  if (count_ == 1) {
    min_ = max_ = value;
  } else {
    min_ = std::min(min_, value);
    max_ = std::max(max_, value);
  }
  const double delta = value - mean_;
  mean_ += delta / static_cast<double>(count_);
  m2_ += delta * (value - mean_);
}

Summary RunningSummary::summary() const {
  Summary s;
  s.count = count_;
  if (count_ == 0) return s;
  s.mean = mean_;
  s.min = min_;
  s.max = max_;
  if (count_ < 2) return s;
  s.variance = m2_ / static_cast<double>(count_ - 1);
  s.sd = std::sqrt(s.variance);
  return s;
}

namespace {

double quantile_of_sorted(const std::vector<double>& sorted, double q) {
  if (!(q >= 0.0 && q <= 1.0)) {
    throw StatsError("quantile: q = " + std::to_string(q) + "; expected 0 <= q <= 1");
  }
  const double h = static_cast<double>(sorted.size() - 1) * q;
  const double floor_h = std::floor(h);
  const std::size_t k = static_cast<std::size_t>(floor_h);
  if (k + 1 >= sorted.size()) return sorted.back();
  return sorted[k] + (h - floor_h) * (sorted[k + 1] - sorted[k]);
}

void sort_checked(std::vector<double>& values) {
  detail::require_at_least("quantile", values.size(), 1);
  detail::require_finite("quantile", "values", values);
  std::sort(values.begin(), values.end());
}

}  // namespace

double quantile(std::vector<double> values, double q) {
  sort_checked(values);
  return quantile_of_sorted(values, q);
}

std::vector<double> quantiles(std::vector<double> values, const std::vector<double>& qs) {
  sort_checked(values);
  std::vector<double> out;
  out.reserve(qs.size());
  for (double q : qs)
    out.push_back(quantile_of_sorted(values, q));
  return out;
}

EqualWidthBins::EqualWidthBins(double lower, double upper, std::size_t count)
    : lower_(lower), upper_(upper), count_(count), tolerance_(1e-12 * (upper - lower)) {
  if (!std::isfinite(lower) || !std::isfinite(upper) || !(lower < upper) || count == 0) {
    throw StatsError("EqualWidthBins: range [" + std::to_string(lower) + ", " +
                     std::to_string(upper) + "] with " + std::to_string(count) +
                     " classes; expected finite lower < upper and at least one class");
  }
}

double EqualWidthBins::edge(std::size_t i) const {
  if (i >= count_) return upper_;
  return lower_ + (upper_ - lower_) * static_cast<double>(i) / static_cast<double>(count_);
}

std::optional<std::size_t> EqualWidthBins::index_of(double value) const {
  if (std::isnan(value)) return std::nullopt;
  if (value < lower_ - tolerance_ || value > upper_ + tolerance_) return std::nullopt;
  const double width = (upper_ - lower_) / static_cast<double>(count_);
  const double guess = std::floor((value - lower_) / width);
  std::size_t k = guess <= 0.0 ? 0 : std::min(static_cast<std::size_t>(guess), count_ - 1);
  // The division above can land one class off near an edge; settle against
  // the edges themselves (on an edge, within tolerance, means the upper class).
  while (k + 1 < count_ && value >= edge(k + 1) - tolerance_)
    ++k;
  while (k > 0 && value < edge(k) - tolerance_)
    --k;
  return k;
}

}  // namespace db::stats
