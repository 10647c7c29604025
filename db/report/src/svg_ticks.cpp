// Axis ticks and their labels for db::svg (see svg_plot.hpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "db/report/svg_plot.hpp"
#include "svg_detail.hpp"

namespace db::report::svg {
namespace {

using detail::number;

// 10^e as the nearest double (exact for |e| <= 22, which covers every
// range a report draws; pow is correctly rounded on glibc beyond that).
double power_of_ten(int e) {
  return std::pow(10.0, e);
}

// mantissa * 10^e, rounded once: dividing by an exact 10^-e gives the
// nearest double to a decimal like 0.6, where mantissa * 0.1 would not.
double scaled(double mantissa, int e) {
  return e >= 0 ? mantissa * power_of_ten(e) : mantissa / power_of_ten(-e);
}

// Decimal places needed to write `step` exactly (0.25 -> 2, 500 -> 0).
int decimals_of(double step) {
  step = std::fabs(step);
  for (int d = 0; d < 15; ++d) {
    const double s = step * power_of_ten(d);
    // An integer up to the rounding of the scaling (relative, as step may be 1e-10).
    if (s >= 0.5 && std::fabs(s - std::round(s)) <= 1e-9 * s) return d;
  }
  return 15;
}

std::string superscript(int e) {
  static const char* const kDigits[] = {"⁰", "¹", "²", "³", "⁴", "⁵", "⁶", "⁷", "⁸", "⁹"};
  std::string out = e < 0 ? "⁻" : "";
  const std::string digits = std::to_string(std::abs(e));
  for (char c : digits)
    out += kDigits[c - '0'];
  return out;
}

}  // namespace

std::vector<double> nice_ticks(double lo, double hi, int target_count) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi)
    throw std::invalid_argument("nice_ticks: range [" + number(lo) + ", " + number(hi) +
                                "] must be finite with lo <= hi");
  if (target_count < 2)
    throw std::invalid_argument("nice_ticks: target_count " + std::to_string(target_count) +
                                " must be >= 2");
  const double magnitude = std::max(std::fabs(lo), std::fabs(hi));
  if (hi - lo <= 1e-12 * magnitude) {
    if (magnitude == 0) {
      lo = -1;
      hi = 1;
    } else {
      const double v = 0.5 * (lo + hi);
      lo = v - 0.05 * std::fabs(v);
      hi = v + 0.05 * std::fabs(v);
    }
  }
  const double raw = (hi - lo) / (target_count - 1);
  const int e0 = static_cast<int>(std::floor(std::log10(raw)));
  // Candidate steps {1, 2, 5} x 10^e around the raw step; the tolerance keeps
  // lo/step = 2.9999999999 from adding a tick below a range that starts on one.
  constexpr double kTolerance = 1e-9;
  double best_mantissa = 1, best_k0 = 0, best_k1 = 0;
  int best_e = e0, best_miss = std::numeric_limits<int>::max();
  for (int e = e0 - 1; e <= e0 + 1; ++e) {
    for (double m : {1.0, 2.0, 5.0}) {
      const double step = scaled(m, e);
      const double k0 = std::floor(lo / step + kTolerance);
      const double k1 = std::ceil(hi / step - kTolerance);
      const int count = static_cast<int>(k1 - k0) + 1;
      const int miss = std::abs(count - target_count);
      if (miss <= best_miss) {  // candidates ascend, so a tie keeps the larger step
        best_miss = miss;
        best_mantissa = m;
        best_e = e;
        best_k0 = k0;
        best_k1 = k1;
      }
    }
  }
  std::vector<double> ticks;
  for (double k = best_k0; k <= best_k1; ++k)
    ticks.push_back(scaled(k * best_mantissa, best_e) + 0.0);  // + 0.0: no "-0"
  return ticks;
}

std::vector<double> nice_log_ticks(double lo, double hi, int target_count) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo <= 0 || lo > hi)
    throw std::invalid_argument("nice_log_ticks: range [" + number(lo) + ", " + number(hi) +
                                "] must be finite with 0 < lo <= hi");
  target_count = std::max(target_count, 2);
  constexpr double kTolerance = 1e-9;
  int k0 = static_cast<int>(std::floor(std::log10(lo) + kTolerance));
  int k1 = static_cast<int>(std::ceil(std::log10(hi) - kTolerance));
  if (k1 == k0) ++k1;
  std::vector<double> ticks;
  if (k1 - k0 <= 2) {
    // Few decades: 1, 2, 5 x 10^k, trimmed to the last one <= lo and the first >= hi.
    std::vector<double> all;
    for (int k = k0; k <= k1; ++k)
      for (double m : {1.0, 2.0, 5.0})
        all.push_back(scaled(m, k));
    size_t first = 0, last = all.size() - 1;
    while (first + 1 < all.size() && all[first + 1] <= lo * (1 + kTolerance))
      ++first;
    while (last > first + 1 && all[last - 1] >= hi * (1 - kTolerance))
      --last;
    ticks.assign(all.begin() + first, all.begin() + last + 1);
    return ticks;
  }
  // Many decades: every stride-th decade, the smallest stride giving at most
  // target_count + 1 ticks (3 gives the engineering steps 10^-3, 1, 10^3).
  int stride = 1;
  for (int s : {1, 2, 3, 5, 10, 20, 50, 100}) {
    stride = s;
    const int a = static_cast<int>(std::floor(static_cast<double>(k0) / s));
    const int b = static_cast<int>(std::ceil(static_cast<double>(k1) / s));
    if (b - a + 1 <= target_count + 1) break;
  }
  k0 = static_cast<int>(std::floor(static_cast<double>(k0) / stride)) * stride;
  k1 = static_cast<int>(std::ceil(static_cast<double>(k1) / stride)) * stride;
  for (int k = k0; k <= k1; k += stride)
    ticks.push_back(scaled(1, k));
  return ticks;
}

std::string tick_label(double value, double step) {
  value += 0.0;  // -0 -> +0: never "-0.0"
  char buf[64];
  const int decimals = decimals_of(step);
  if (value == 0 || (std::fabs(value) < 1e6 && decimals <= 4)) {
    if (value == 0 && decimals > 4) return "0";
    std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
    return buf;
  }
  // value = mantissa x 10^p with 1 <= |mantissa| < 10, written with the
  // places the step needs at that power.
  int p = static_cast<int>(std::floor(std::log10(std::fabs(value))));
  double mantissa = value / scaled(1, p);
  if (std::fabs(mantissa) >= 10 - 1e-9) {
    ++p;
    mantissa /= 10;
  }
  const int places = std::min(decimals_of(std::fabs(step) / scaled(1, p)), 6);
  std::snprintf(buf, sizeof buf, "%.*f", places, mantissa);
  return std::string(buf) + "×10" + superscript(p);
}

}  // namespace db::report::svg
