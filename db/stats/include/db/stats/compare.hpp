// Run comparison: is a figure of this run different from the
// baseline's by more than its statistical uncertainty? A difference is
// flagged only when |difference| > k * standard error.
//
// k trades false alarms against missed regressions: for normal errors a
// single comparison at k = 3 flags a true non-change 0.27 % of the time
// (two-sided), at k = 2 4.6 %; a report compares tens of figures, so the
// default is 3. For small samples the Welch degrees of freedom are returned
// so that a caller can use a Student-t quantile as k instead.
#pragma once

#include <limits>

#include "db/stats/descriptive.hpp"
#include "db/stats/regression.hpp"

namespace db::stats {

struct Difference {
  double difference = 0.0;      // candidate - baseline, in the figure's units
  double standard_error = 0.0;  // of the difference
  double z = 0.0;               // difference / standard_error (+-inf when se == 0)
  // Welch-Satterthwaite degrees of freedom for means; infinity for figures
  // whose standard errors are asymptotic (slopes, intercepts).
  double dof = std::numeric_limits<double>::infinity();
  bool significant = false;  // |difference| > k * standard_error
};

// Welch's comparison of two means from independent samples:
// se^2 = s1^2/n1 + s2^2/n2, dof = se^4 / ((s1^2/n1)^2/(n1-1) + (s2^2/n2)^2/(n2-1))
// (Welch, Biometrika 34 (1947) 28). With both variances 0 any non-zero
// difference is significant.
// Preconditions: both counts >= 2 with finite variance, k > 0; throws StatsError.
Difference compare_means(const Summary& candidate, const Summary& baseline, double k = 3.0);

// Difference of two independent estimates with standard errors (e.g. the
// slopes or intercepts of two runs' fits): se = sqrt(se_c^2 + se_b^2).
// Preconditions: finite values, standard errors >= 0, k > 0; throws StatsError.
Difference compare_estimates(double candidate, double candidate_se, double baseline,
                             double baseline_se, double k = 3.0);

// Two-sided tail probability of k standard errors: P(|T| > k) for Student's
// t with `dof` degrees of freedom, or for the normal distribution when dof is
// infinite: 2 (1 - F(k)). Computed as the regularized incomplete beta
// I_{dof/(dof+k^2)}(dof/2, 1/2) (Abramowitz & Stegun 26.7.1) by its continued
// fraction (Lentz), to about 1e-14 relative.
// Preconditions: k >= 0 finite, dof > 0 (or +infinity); throws StatsError.
double two_sided_tail(double k, double dof);

// The k with two_sided_tail(k, dof) = p: the threshold that keeps a
// comparison's false-alarm rate at p for a Student-t figure (e.g. a paired
// mean over n positions, dof = n - 1) as for a normal one. By bisection to
// 1e-12 relative. Preconditions: 0 < p < 1, dof > 0 (or +infinity); throws
// StatsError.
double two_sided_threshold(double p, double dof);

// Slopes of two independent line fits ([y]/[x]), by compare_estimates:
// finite slopes and standard errors >= 0, k > 0; throws StatsError.
Difference compare_slopes(const LineFit& candidate, const LineFit& baseline, double k = 3.0);

}  // namespace db::stats
