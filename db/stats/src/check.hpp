// Input checks shared by the db_stats sources (private header).
#pragma once

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "db/stats/error.hpp"

namespace db::stats::detail {

inline void require_same_size(const char* function, const std::vector<double>& a,
                              const std::vector<double>& b) {
  if (a.size() != b.size()) {
    throw StatsError(std::string(function) + ": the two inputs hold " + std::to_string(a.size()) +
                     " and " + std::to_string(b.size()) + " values; expected equal lengths");
  }
}

inline void require_at_least(const char* function, std::size_t n, std::size_t minimum) {
  if (n < minimum) {
    throw StatsError(std::string(function) + ": " + std::to_string(n) +
                     " values; expected at least " + std::to_string(minimum));
  }
}

inline void require_finite(const char* function, const char* what, const std::vector<double>& v) {
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      throw StatsError(std::string(function) + ": " + what + "[" + std::to_string(i) +
                       "] = " + std::to_string(v[i]) + "; expected a finite number");
    }
  }
}

// Mean with one correction pass: the second sum of (v - m) removes the
// rounding error of the first (Higham, Accuracy and Stability, §1.9).
inline double accurate_mean(const std::vector<double>& v) {
  double sum = 0.0;
  for (double x : v)
    sum += x;
  const double n = static_cast<double>(v.size());
  double m = sum / n;
  double correction = 0.0;
  for (double x : v)
    correction += x - m;
  return m + correction / n;
}

// Means and centred second moments of paired samples (two-pass: the sums of
// products are taken about the accurate means, which keeps NIST's offset
// datasets exact).
struct CentredMoments {
  double mean_x = 0, mean_y = 0;
  double sxx = 0, syy = 0, sxy = 0;  // sums of dx^2, dy^2, dx dy
};

inline CentredMoments centred_moments(const std::vector<double>& x, const std::vector<double>& y) {
  CentredMoments m;
  m.mean_x = accurate_mean(x);
  m.mean_y = accurate_mean(y);
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double dx = x[i] - m.mean_x, dy = y[i] - m.mean_y;
    m.sxx += dx * dx;
    m.syy += dy * dy;
    m.sxy += dx * dy;
  }
  return m;
}

}  // namespace db::stats::detail
