// Run comparison: each solver's figures against the baseline's,
// flagged only where the difference exceeds k standard errors.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "db/report/report.hpp"
#include "db/stats/error.hpp"

namespace db::report {
namespace {

// direction: +1 when larger is worse (errors, failure rates), 0 when a
// change is neither (slope, intercept: either way is away from or towards
// the truth depending on the side; times: machine-dependent).
void add(std::vector<ComparedFigure>& out, const SolverStudy& c, const std::string& figure,
         double candidate, double baseline, const stats::Difference& d, int direction) {
  ComparedFigure f;
  f.solver = c.solver;
  f.scope = c.scope;
  f.figure = figure;
  f.candidate = candidate;
  f.baseline = baseline;
  f.difference = d;
  f.counted = direction > 0;
  out.push_back(f);
}

void compare_summaries(std::vector<ComparedFigure>& out, const SolverStudy& c,
                       const std::string& figure, const stats::Summary& a, const stats::Summary& b,
                       double k, int direction) {
  if (a.count < 2 || b.count < 2) return;
  try {
    add(out, c, figure, a.mean, b.mean, stats::compare_means(a, b, k), direction);
  } catch (const stats::StatsError&) {
    // Non-finite variance: nothing to compare.
  }
}

// A per-position mean of this run against the baseline's. Paired by plan
// index when both runs ran the same plan (their run descriptions' plan_json
// are identical text, so plan index i is the same commanded position in both)
// and share at least two measured positions: the differences d_p of the same
// positions are independent across positions, and their mean over
// sd(d)/sqrt(n) tests the change without the spread of the errors over
// distance (which dominates Welch's standard error on a sweep over 0.1-1 m).
// Otherwise Welch on the two runs' per-position summaries, and the figure's
// name says why: pairing positions of different plans would compare errors at
// different distances as if they were the same position's.
void compare_positions(std::vector<ComparedFigure>& out, const SolverStudy& c, const SolverStudy& b,
                       bool same_plan, const std::string& figure, double PositionMeans::*member,
                       const stats::Summary& c_all, const stats::Summary& b_all, double k) {
  if (!same_plan) {
    compare_summaries(out, c, figure + ", Welch (the runs' plans differ: not paired)", c_all, b_all,
                      k, +1);
    return;
  }
  stats::RunningSummary diff, c_mean, b_mean;
  std::size_t j = 0;
  for (const PositionMeans& p : c.per_position) {
    while (j < b.per_position.size() && b.per_position[j].plan_index < p.plan_index)
      ++j;
    if (j == b.per_position.size() || b.per_position[j].plan_index != p.plan_index) continue;
    const double x = p.*member, y = b.per_position[j].*member;
    if (!std::isfinite(x) || !std::isfinite(y)) continue;
    diff.add(x - y);
    c_mean.add(x);
    b_mean.add(y);
  }
  const stats::Summary d = diff.summary();
  if (d.count < 2) {
    compare_summaries(out, c, figure + ", Welch (fewer than two shared positions)", c_all, b_all, k,
                      +1);
    return;
  }
  const double se = d.sd / std::sqrt(static_cast<double>(d.count));
  try {
    // The mean of n differences over their own sd: Student's t, n - 1 dof.
    stats::Difference difference = stats::compare_estimates(d.mean, se, 0.0, 0.0, k);
    difference.dof = static_cast<double>(d.count - 1);
    add(out, c, figure + ", paired over " + std::to_string(d.count) + " positions",
        c_mean.summary().mean, b_mean.summary().mean, difference, +1);
  } catch (const stats::StatsError&) {
    // A non-finite difference: nothing to compare.
  }
}

// Failure rate x/n against the baseline's, with the pooled two-proportion
// standard error sqrt(p (1 - p) (1/n1 + 1/n2)), p = (x1 + x2) / (n1 + n2):
// under "no change" both runs share p, and unlike separate binomial errors it
// does not call 1 failure in 10^5 significant against a baseline with none.
void compare_failure_rate(std::vector<ComparedFigure>& out, const SolverStudy& c,
                          const SolverStudy& b, double k) {
  const double n1 = static_cast<double>(c.estimates - c.skipped);
  const double n2 = static_cast<double>(b.estimates - b.skipped);
  if (n1 < 1 || n2 < 1) return;
  const double x1 = static_cast<double>(c.failed), x2 = static_cast<double>(b.failed);
  const double p = (x1 + x2) / (n1 + n2);
  const double se = std::sqrt(p * (1 - p) * (1 / n1 + 1 / n2));
  if (!(se > 0)) return;  // no failures in either run
  add(out, c, "failure rate", x1 / n1, x2 / n2,
      stats::compare_estimates(x1 / n1, se, x2 / n2, 0.0, k), +1);
}

// Bias of each distance class against the baseline's: the positions' mean
// errors are independent samples, so Welch applies (frames of one position
// are not independent). Flagged, not counted: tens of classes per solver
// would make a false alarm likely.
void compare_classes(std::vector<ComparedFigure>& out, const SolverStudy& c, const SolverStudy& b,
                     double k) {
  for (std::size_t i = 0; i < c.classes.size() && i < b.classes.size(); ++i) {
    const DistanceClassStudy& cc = c.classes[i];
    const DistanceClassStudy& bc = b.classes[i];
    stats::Summary cs, bs;
    cs.count = cc.positions;
    cs.mean = cc.bias_m;
    cs.variance = cc.bias_sd_m * cc.bias_sd_m;
    bs.count = bc.positions;
    bs.mean = bc.bias_m;
    bs.variance = bc.bias_sd_m * bc.bias_sd_m;
    char name[80];
    std::snprintf(name, sizeof name, "bias (m), class %.2f-%.2f m", cc.lower_m, cc.upper_m);
    compare_summaries(out, c, name, cs, bs, k, 0);
  }
}

}  // namespace

bool regressed(const std::vector<ComparedFigure>& comparison) {
  return std::any_of(comparison.begin(), comparison.end(),
                     [](const ComparedFigure& f) { return f.worse; });
}

bool same_plan_of(const RunStudy& candidate, const RunStudy& baseline) {
  return candidate.run.description.plan_json == baseline.run.description.plan_json;
}

std::vector<ComparedFigure> compare_runs(const RunStudy& candidate, const RunStudy& baseline,
                                         double k) {
  if (!(k > 0) || !std::isfinite(k)) {
    throw stats::StatsError("compare_runs: k is " + std::to_string(k) +
                            ", expected a finite threshold > 0 (standard errors)");
  }
  std::vector<ComparedFigure> out;
  const bool same_plan = same_plan_of(candidate, baseline);
  for (const SolverStudy& c : candidate.solvers) {
    const SolverStudy* b = baseline.find(c.solver, c.scope);
    if (b == nullptr) continue;
    compare_positions(out, c, *b, same_plan, "mean |distance error| (m)",
                      &PositionMeans::abs_error_m, c.position_abs_error_m, b->position_abs_error_m,
                      k);
    compare_positions(out, c, *b, same_plan, "mean reprojection error (px)",
                      &PositionMeans::reprojection_px, c.position_reprojection_px,
                      b->position_reprojection_px, k);
    if (c.position_generalization_px.count > 0 && b->position_generalization_px.count > 0) {
      compare_positions(out, c, *b, same_plan, "mean generalization error (px)",
                        &PositionMeans::generalization_px, c.position_generalization_px,
                        b->position_generalization_px, k);
    }
    compare_failure_rate(out, c, *b, k);
    if (c.ols && b->ols) {
      add(out, c, "slope a", c.ols->slope, b->ols->slope, stats::compare_slopes(*c.ols, *b->ols, k),
          0);
      add(out, c, "intercept b (m)", c.ols->intercept, b->ols->intercept,
          stats::compare_estimates(c.ols->intercept, c.ols->intercept_se, b->ols->intercept,
                                   b->ols->intercept_se, k),
          0);
    }
    compare_summaries(out, c, "time per pose (µs)", c.time_us, b->time_us, k, 0);
    compare_classes(out, c, *b, k);
  }
  const auto m =
      std::count_if(out.begin(), out.end(), [](const ComparedFigure& f) { return f.counted; });
  // The family's false-alarm rate is that of one normal comparison at k
  // (Bonferroni over the m counted figures); each figure's threshold keeps
  // its share of it under its own distribution: Student's t for a paired or
  // Welch mean over few positions (the normal k would flag a paired mean over
  // 3 positions at k = 3 about 9.5 % of the time instead of 0.27 %).
  const double family_tail = stats::two_sided_tail(k, std::numeric_limits<double>::infinity()) /
                             static_cast<double>(std::max<std::ptrdiff_t>(1, m));
  for (ComparedFigure& f : out) {
    const double dof =
        f.difference.dof > 0 ? f.difference.dof : std::numeric_limits<double>::infinity();
    f.regression_k = std::max(k, stats::two_sided_threshold(family_tail, dof));
    const bool beyond = std::fabs(f.difference.z) > f.regression_k;
    f.worse = f.counted && beyond && f.difference.difference > 0;
    f.better = f.counted && beyond && f.difference.difference < 0;
  }
  return out;
}

}  // namespace db::report
