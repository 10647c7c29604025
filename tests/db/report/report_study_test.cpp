// db::report::study_run on synthetic runs with known truth (tests/support/synthetic_run):
// the report must recover what the fixture put in, within tolerances derived
// from the sampling distributions of the statistics it reports.
//
// The fixture draws from SyntheticRunSpec::seed (fixed), so every run sees
// the same numbers and these tests are deterministic. The tolerances say how
// unusual a draw would have to be to fail: 4 standard errors is 6e-5 per
// check under normality, so with another seed one of the file's ~80 checks
// would fail with probability about 5e-3. A new seed is therefore run once
// before it is committed.
#include <gtest/gtest.h>

#include <cmath>

#include "db/report/report.hpp"
#include "store_fixture.hpp"
#include "synthetic_run.hpp"

namespace {

using rig_test::SyntheticRunSpec;

// One database for the whole suite: writing it is the slow part.
class ReportStudy : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new db_test::ScratchDir();
    spec_ = new SyntheticRunSpec();
    spec_->solvers = rig_test::paper_like_solvers();
    spec_->failed_positions = 4;
    rig_test::write_synthetic_run(dir_->file("run.db"), *spec_);
    study_ = new db::report::RunStudy(
        db::report::study_run(dir_->file("run.db"), db::report::ReportOptions{}));
  }
  static void TearDownTestSuite() {
    delete study_;
    delete spec_;
    delete dir_;
  }
  static const db::report::SolverStudy& solver(const std::string& name, const std::string& scope) {
    const db::report::SolverStudy* s = study_->find(name, scope);
    if (s == nullptr) throw std::runtime_error("no " + name + "/" + scope);
    return *s;
  }
  static const rig_test::SyntheticSolver& truth(const std::string& name) {
    for (const auto& s : spec_->solvers)
      if (s.name == name) return s;
    throw std::runtime_error("no solver " + name);
  }
  static db_test::ScratchDir* dir_;
  static SyntheticRunSpec* spec_;
  static db::report::RunStudy* study_;
};
db_test::ScratchDir* ReportStudy::dir_ = nullptr;
SyntheticRunSpec* ReportStudy::spec_ = nullptr;
db::report::RunStudy* ReportStudy::study_ = nullptr;

TEST_F(ReportStudy, CountsPositionsFramesAndEstimatesOfTheRun) {
  const int ok = spec_->positions - spec_->failed_positions;
  EXPECT_EQ(study_->positions, static_cast<std::size_t>(spec_->positions));
  EXPECT_EQ(study_->failed_positions, static_cast<std::size_t>(spec_->failed_positions));
  EXPECT_EQ(study_->frames, static_cast<std::size_t>(ok * spec_->frames_per_position));
  // 4 solvers x 2 scopes per frame.
  EXPECT_EQ(study_->estimates, static_cast<std::size_t>(ok * spec_->frames_per_position * 8));
  EXPECT_EQ(study_->solvers.size(), 8u);
  EXPECT_TRUE(study_->distance_bounds_recorded);
  EXPECT_TRUE(study_->visible_markers_recorded);
  EXPECT_TRUE(study_->viewing_angles_recorded);
  ASSERT_EQ(study_->events.size(), 2u);
  EXPECT_EQ(study_->events[0].kind, "pause");
}

// OLS of y = a x + b + e, e ~ N(0, sigma^2) iid: the estimates are unbiased
// and normal with the standard errors reported, so |a_hat - a| < 4 se fails
// with probability 6e-5 per coefficient. The reported se is sigma_hat /
// sqrt(Sxx); sigma_hat^2 (n-2)/sigma^2 is chi-square with n-2 dof, so
// se_reported / se_true has relative sd ~ 1 / sqrt(2 (n-2)): allow 4 of those.
TEST_F(ReportStudy, RecoversSlopeInterceptAndTheirStandardErrors) {
  for (const char* name : {"analytic", "hybrid_oi", "ekf", "ippe"}) {
    const auto& t = truth(name);
    if (t.efficiency > 0) continue;  // heteroscedastic by design; see the efficiency test
    const db::report::SolverStudy& s = solver(name, "0");
    ASSERT_TRUE(s.ols.has_value()) << name;
    EXPECT_NEAR(s.ols->slope, t.slope, 4 * s.ols->slope_se) << name;
    EXPECT_NEAR(s.ols->intercept, t.intercept_m, 4 * s.ols->intercept_se) << name;
    double sxx = 0, mean = 0;
    std::vector<double> x;
    for (int i = 0; i < spec_->positions - spec_->failed_positions; ++i)
      for (int f = 0; f < spec_->frames_per_position; ++f)
        x.push_back(rig_test::synthetic_true_distance(*spec_, i));
    // Only converged estimates are in the fit; the ekf's 5 % failures thin x
    // at random, which changes Sxx by ~5 %: compare against the fit's own n.
    for (double v : x)
      mean += v / x.size();
    for (double v : x)
      sxx += (v - mean) * (v - mean);
    sxx *= static_cast<double>(s.ols->n) / static_cast<double>(x.size());
    const double se_true = t.frame_sd_m / std::sqrt(sxx);
    const double rel = 4.0 / std::sqrt(2.0 * (s.ols->n - 2));
    EXPECT_NEAR(s.ols->slope_se / se_true, 1.0, rel + 0.03) << name;  // + Sxx thinning
    EXPECT_NEAR(s.ols->residual_sd, t.frame_sd_m, rel * t.frame_sd_m) << name;
  }
}

// With an (almost) exact true distance the error-variance ratio is huge and
// Deming regression is ordinary least squares of y on x (Deming's delta ->
// infinity limit).
TEST(ReportStudyOptions, DemingEqualsOlsWhenTheTrueDistanceIsExact) {
  db_test::ScratchDir dir;
  SyntheticRunSpec spec;
  spec.solvers = {rig_test::paper_like_solvers()[1]};
  rig_test::write_synthetic_run(dir.file("run.db"), spec);
  db::report::ReportOptions options;
  options.true_distance_sd_m = 1e-9;  // delta ~ (1.5e-3 / 1e-9)^2 ~ 2e12
  const db::report::RunStudy st = db::report::study_run(dir.file("run.db"), options);
  const db::report::SolverStudy* s = st.find("hybrid_oi", "0");
  ASSERT_NE(s, nullptr);
  ASSERT_TRUE(s->ols && s->deming);
  EXPECT_GT(s->deming_delta, 1e10);
  EXPECT_NEAR(s->deming->slope, s->ols->slope, 1e-6 * s->ols->slope_se);
  EXPECT_NEAR(s->deming->intercept, s->ols->intercept, 1e-6 * s->ols->intercept_se);
}

// Class means and variances of the error against the model: in class c the
// error is (a-1) x + b + e, so its mean is (a-1) mean(x_c) + b (sd of the
// sample mean sigma/sqrt(n) plus the x spread) and its variance sigma^2 +
// (a-1)^2 var(x_c), with the chi-square relative sd sqrt(2/(n-1)).
TEST_F(ReportStudy, RecoversClassMeansAndVariancesOfTheError) {
  const auto& t = truth("hybrid_oi");
  const db::report::SolverStudy& s = solver("hybrid_oi", "0");
  ASSERT_EQ(s.classes.size(), 10u);
  std::size_t total = 0;
  for (const db::report::DistanceClassStudy& c : s.classes) {
    std::vector<double> x;
    for (int i = 0; i < spec_->positions - spec_->failed_positions; ++i) {
      const double d = rig_test::synthetic_true_distance(*spec_, i);
      if (d >= c.lower_m && d < c.upper_m)
        for (int f = 0; f < spec_->frames_per_position; ++f)
          x.push_back(d);
    }
    ASSERT_EQ(c.error_m.count, x.size()) << c.lower_m;
    total += c.error_m.count;
    if (x.size() < 3) continue;
    double mx = 0, vx = 0;
    for (double v : x)
      mx += v / x.size();
    for (double v : x)
      vx += (v - mx) * (v - mx) / (x.size() - 1);
    const double n = static_cast<double>(x.size());
    const double expected_mean = (t.slope - 1) * mx + t.intercept_m;
    const double expected_var = t.frame_sd_m * t.frame_sd_m + (t.slope - 1) * (t.slope - 1) * vx;
    EXPECT_NEAR(c.error_m.mean, expected_mean, 4 * std::sqrt(expected_var / n)) << c.lower_m;
    EXPECT_NEAR(c.error_m.variance, expected_var, 4 * std::sqrt(2 / (n - 1)) * expected_var)
        << c.lower_m;
  }
  EXPECT_EQ(total, s.used);
}

// Jitter is the frame-to-frame sd (frame_sd_m) and bias the mean error
// (a-1) d + b: the pooled variance has (frames-1) dof per position.
TEST_F(ReportStudy, SeparatesJitterFromBiasPerClass) {
  const auto& t = truth("hybrid_oi");
  const db::report::SolverStudy& s = solver("hybrid_oi", "0");
  for (const db::report::DistanceClassStudy& c : s.classes) {
    ASSERT_GT(c.positions, 2u);
    const double dof = static_cast<double>(c.positions * (spec_->frames_per_position - 1));
    EXPECT_NEAR(c.jitter_m, t.frame_sd_m, 4 * std::sqrt(1 / (2 * dof)) * t.frame_sd_m);
    const double mid = 0.5 * (c.lower_m + c.upper_m);
    const double half_width = 0.5 * (c.upper_m - c.lower_m);
    // The positions' mean error has sd frame_sd / sqrt(frames); the class
    // mean of positions spread over the class differs from the mid value by
    // at most (a-1) half_width.
    const double se = t.frame_sd_m / std::sqrt(spec_->frames_per_position * c.positions);
    EXPECT_NEAR(c.bias_m, (t.slope - 1) * mid + t.intercept_m, 4 * se + (t.slope - 1) * half_width);
  }
}

// Corners jitter by corner_noise_px per coordinate; the pooled estimate has
// (frames-1) * 8 * markers dof per position.
TEST_F(ReportStudy, EstimatesCornerNoiseFromTheFrameToFrameJitterOfTheCorners) {
  for (const db::report::ClassCornerNoise& c : study_->corner_noise) {
    ASSERT_GT(c.dof, 100u);
    EXPECT_NEAR(c.sigma_px, spec_->corner_noise_px,
                4 * std::sqrt(1.0 / (2.0 * c.dof)) * spec_->corner_noise_px);
  }
}

// ippe's frame sd is sqrt(2) * sigma * bound(d): efficiency 2. The ratio of
// two independent variance estimates has relative sd sqrt(2/dof1 + 2/dof2).
TEST_F(ReportStudy, EfficiencyIsTheVarianceOverTheCramerRaoBound) {
  const auto& t = truth("ippe");
  // The pooled jitter variance is a weighted sum of chi-squares whose
  // weights b_p^2 vary with d^4 across the class: its effective dof is
  // (sum w)^2 / sum w^2 with w = (frames-1) b_p^2 (Satterthwaite). A constant
  // factor of the bounds (scope "target" has half of scope "0"'s) cancels.
  auto jitter_dof = [&](const db::report::DistanceClassStudy& c) {
    double sw = 0, sw2 = 0;
    for (int p = 0; p < spec_->positions - spec_->failed_positions; ++p) {
      const double d = rig_test::synthetic_true_distance(*spec_, p);
      if (d < c.lower_m || d >= c.upper_m) continue;
      const double w =
          (spec_->frames_per_position - 1) * std::pow(rig_test::synthetic_bound(*spec_, d), 2);
      sw += w;
      sw2 += w * w / (spec_->frames_per_position - 1);
    }
    return sw * sw / sw2;
  };
  const db::report::SolverStudy& s = solver("ippe", "0");
  for (std::size_t i = 0; i < s.classes.size(); ++i) {
    const db::report::DistanceClassStudy& c = s.classes[i];
    const double dof_corner = static_cast<double>(study_->corner_noise[i].dof);
    const double rel = std::sqrt(2 / jitter_dof(c) + 2 / dof_corner);
    EXPECT_NEAR(c.efficiency, t.efficiency, 4 * rel * t.efficiency) << c.lower_m;
  }
  // Scope "target" has its own bound (half the pose marker's), so its
  // efficiency is 4x; its tolerance is derived the same way.
  const db::report::SolverStudy& target = solver("ippe", "target");
  const db::report::DistanceClassStudy& c5 = target.classes[5];
  const double rel5 = std::sqrt(2 / jitter_dof(c5) + 2.0 / study_->corner_noise[5].dof);
  EXPECT_NEAR(c5.efficiency, 4 * t.efficiency, 4 * rel5 * 4 * t.efficiency);
}

TEST_F(ReportStudy, CountsSkippedAndFailedEstimatesButExcludesThemFromAccuracy) {
  const db::report::SolverStudy& skipped = solver("analytic", "target");
  EXPECT_EQ(skipped.skipped, skipped.estimates);
  EXPECT_EQ(skipped.used, 0u);
  EXPECT_EQ(skipped.failed, 0u);
  EXPECT_FALSE(skipped.ols.has_value());
  EXPECT_EQ(skipped.error_m.count, 0u);

  // ekf: 5 % failures, binomial: |failed - n p| < 4 sqrt(n p (1 - p)).
  const db::report::SolverStudy& ekf = solver("ekf", "0");
  const double n = static_cast<double>(ekf.estimates);
  EXPECT_NEAR(static_cast<double>(ekf.failed), 0.05 * n, 4 * std::sqrt(n * 0.05 * 0.95));
  EXPECT_EQ(ekf.failures_by_termination.at("max_iterations"), ekf.failed);
  EXPECT_EQ(ekf.used + ekf.failed, ekf.estimates);
  EXPECT_EQ(ekf.error_m.count, ekf.used);
  EXPECT_EQ(ekf.time_us.count, ekf.estimates);  // time counts every applicable estimate
}

TEST_F(ReportStudy, CountsAmbiguousEstimatesAndFlips) {
  const db::report::SolverStudy& ippe = solver("ippe", "0");
  // ratio 0.9 >= threshold 0.8 on every ippe estimate (none fails).
  EXPECT_EQ(ippe.ambiguity_checked, ippe.estimates);
  EXPECT_EQ(ippe.ambiguous, ippe.estimates);
  EXPECT_EQ(solver("hybrid_oi", "0").ambiguity_checked, 0u);
  // 10 % of frames flipped by 60 degrees (> 20): binomial bounds.
  const double n = static_cast<double>(ippe.flip_checked);
  EXPECT_EQ(ippe.flip_checked, ippe.estimates);
  EXPECT_NEAR(static_cast<double>(ippe.flips), 0.1 * n, 4 * std::sqrt(n * 0.1 * 0.9));
  EXPECT_EQ(solver("hybrid_oi", "0").flips, 0u);
  std::size_t by_angle = 0;
  for (const auto& a : ippe.by_viewing_angle)
    by_angle += a.flips;
  EXPECT_EQ(by_angle, ippe.flips);  // every viewing angle of the fixture is in [0, 60)
}

// Marker 3 is never detected beyond marker3_lost_beyond_m, i.e. at sides
// below 0.05 * 720 / 0.8 = 45 px; every other visible marker always is.
TEST_F(ReportStudy, DetectionRateFallsWhereTheSmallestMarkerIsLost) {
  ASSERT_EQ(study_->marker_sizes.size(), 10u);
  const double lost_below_px = 0.05 * 720.0 / spec_->marker3_lost_beyond_m;
  std::size_t expected = 0;
  for (const db::report::MarkerSizeClass& m : study_->marker_sizes) {
    expected += m.expected;
    if (m.expected == 0) continue;
    const double rate = static_cast<double>(m.detected) / static_cast<double>(m.expected);
    if (m.lower_px >= lost_below_px) {
      EXPECT_EQ(rate, 1.0) << m.lower_px;
    }
    if (m.upper_px < lost_below_px) {
      EXPECT_EQ(rate, 0.75) << m.lower_px;
    }
  }
  EXPECT_EQ(expected, 4 * study_->frames);
}

TEST_F(ReportStudy, SummarisesStageTimes) {
  const auto it =
      std::find_if(study_->stages.begin(), study_->stages.end(),
                   [](const db::report::StageStudy& s) { return s.stage == "solve:ekf"; });
  ASSERT_NE(it, study_->stages.end());
  EXPECT_EQ(it->seconds.count,
            static_cast<std::size_t>(spec_->positions - spec_->failed_positions));
  EXPECT_NEAR(it->median_s, 1e-6 * 5000 * spec_->frames_per_position, 1e-15);
}

TEST(ReportStudyOptions, SaysWhatASchemaOneWriterDidNotRecord) {
  db_test::ScratchDir dir;
  SyntheticRunSpec spec;
  spec.positions = 30;
  spec.solvers = {rig_test::paper_like_solvers()[3]};
  spec.record_physics = false;
  rig_test::write_synthetic_run(dir.file("run.db"), spec);
  const db::report::RunStudy st =
      db::report::study_run(dir.file("run.db"), db::report::ReportOptions{});
  EXPECT_FALSE(st.distance_bounds_recorded);
  EXPECT_FALSE(st.visible_markers_recorded);
  EXPECT_FALSE(st.viewing_angles_recorded);
  const db::report::SolverStudy* s = st.find("ippe", "0");
  ASSERT_NE(s, nullptr);
  for (const auto& c : s->classes)
    EXPECT_TRUE(std::isnan(c.efficiency));
  for (const auto& a : s->by_viewing_angle)
    EXPECT_EQ(a.flip_checked, 0u);
  // Corner quality is still there, against the detected side; no rate.
  ASSERT_FALSE(st.marker_sizes.empty());
  for (const auto& m : st.marker_sizes)
    EXPECT_EQ(m.expected, 0u);
}

}  // namespace

namespace {

// A plan's end points read back a few micrometres outside [0.10, 1.00] m
// stay in the edge classes; positions well outside are counted apart.
TEST(ReportStudyOptions, EdgePositionsJustOutsideTheRangeStayInTheEdgeClasses) {
  db_test::ScratchDir dir;
  SyntheticRunSpec spec;
  spec.positions = 20;
  spec.solvers = {rig_test::paper_like_solvers()[1]};
  spec.min_distance_m = 0.10 - 0.004;  // within the 5 mm tolerance
  spec.max_distance_m = 1.00 + 0.004;
  rig_test::write_synthetic_run(dir.file("edge.db"), spec);
  const db::report::RunStudy edge = db::report::study_run(dir.file("edge.db"), {});
  EXPECT_EQ(edge.positions_outside_classes, 0u);
  const db::report::SolverStudy* s = edge.find("hybrid_oi", "0");
  ASSERT_NE(s, nullptr);
  std::size_t in_classes = 0;
  for (const auto& c : s->classes)
    in_classes += c.error_m.count;
  EXPECT_EQ(in_classes, s->used);

  spec.max_distance_m = 1.20;  // positions beyond 1.005 m are outside
  rig_test::write_synthetic_run(dir.file("far.db"), spec);
  const db::report::RunStudy far = db::report::study_run(dir.file("far.db"), {});
  std::size_t beyond = 0;
  for (int i = 0; i < spec.positions; ++i)
    beyond += rig_test::synthetic_true_distance(spec, i) > 1.005 ? 1 : 0;
  EXPECT_GT(beyond, 0u);
  EXPECT_EQ(far.positions_outside_classes, beyond);
}

// Failed estimates are not in the ambiguity counts: with 30 % failures the
// denominator is the converged estimates only.
TEST(ReportStudyOptions, AmbiguityCountsConvergedEstimatesOnly) {
  db_test::ScratchDir dir;
  SyntheticRunSpec spec;
  spec.positions = 20;
  rig_test::SyntheticSolver ippe;
  ippe.name = "ippe";
  ippe.ambiguity_ratio = 0.9;
  ippe.failure_rate = 0.3;
  spec.solvers = {ippe};
  rig_test::write_synthetic_run(dir.file("run.db"), spec);
  const db::report::RunStudy st =
      db::report::study_run(dir.file("run.db"), db::report::ReportOptions{});
  const db::report::SolverStudy* s = st.find("ippe", "0");
  ASSERT_NE(s, nullptr);
  ASSERT_GT(s->failed, 0u);  // P(no failure in 60) = 0.7^60 ~ 5e-10
  EXPECT_EQ(s->ambiguity_checked, s->estimates - s->failed - s->skipped);
  EXPECT_EQ(s->ambiguous, s->ambiguity_checked);
  std::size_t by_class = 0;
  for (const db::report::DistanceClassStudy& c : s->classes)
    by_class += c.ambiguity_checked;
  EXPECT_EQ(by_class, s->ambiguity_checked);
}

}  // namespace
