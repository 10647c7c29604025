#include "db/stats_compare.hpp"

#include <cmath>
#include <string>

#include "db/stats_error.hpp"

namespace db::stats {

namespace {

void require_k(const char* function, double k) {
  if (!(k > 0.0) || !std::isfinite(k)) {
    throw StatsError(std::string(function) + ": k = " + std::to_string(k) +
                     "; expected a finite number of standard errors > 0");
  }
}

Difference make(double difference, double se, double k) {
  Difference d;
  d.difference = difference;
  d.standard_error = se;
  if (se > 0.0) {
    d.z = difference / se;
  } else {
    d.z = difference == 0.0 ? 0.0
                            : std::copysign(std::numeric_limits<double>::infinity(), difference);
  }
  d.significant = std::abs(difference) > k * se;
  return d;
}

}  // namespace

Difference compare_means(const Summary& candidate, const Summary& baseline, double k) {
  constexpr const char* kName = "compare_means";
  require_k(kName, k);
  for (const Summary* s : {&candidate, &baseline}) {
    if (s->count < 2 || !std::isfinite(s->variance) || !std::isfinite(s->mean)) {
      throw StatsError(std::string(kName) + ": a sample of " + std::to_string(s->count) +
                       " values with variance " + std::to_string(s->variance) +
                       "; expected at least 2 values and a finite variance");
    }
  }
  const double v1 = candidate.variance / static_cast<double>(candidate.count);
  const double v2 = baseline.variance / static_cast<double>(baseline.count);
  Difference d = make(candidate.mean - baseline.mean, std::sqrt(v1 + v2), k);
  const double den = v1 * v1 / static_cast<double>(candidate.count - 1) +
                     v2 * v2 / static_cast<double>(baseline.count - 1);
  d.dof = den > 0.0 ? (v1 + v2) * (v1 + v2) / den : std::numeric_limits<double>::infinity();
  return d;
}

Difference compare_estimates(double candidate, double candidate_se, double baseline,
                             double baseline_se, double k) {
  constexpr const char* kName = "compare_estimates";
  require_k(kName, k);
  if (!std::isfinite(candidate) || !std::isfinite(baseline) || !(candidate_se >= 0.0) ||
      !(baseline_se >= 0.0) || !std::isfinite(candidate_se) || !std::isfinite(baseline_se)) {
    throw StatsError(std::string(kName) + ": estimates " + std::to_string(candidate) + " +- " +
                     std::to_string(candidate_se) + " and " + std::to_string(baseline) + " +- " +
                     std::to_string(baseline_se) +
                     "; expected finite values and standard errors >= 0");
  }
  return make(candidate - baseline, std::hypot(candidate_se, baseline_se), k);
}

Difference compare_slopes(const LineFit& candidate, const LineFit& baseline, double k) {
  return compare_estimates(candidate.slope, candidate.slope_se, baseline.slope, baseline.slope_se,
                           k);
}

}  // namespace db::stats
