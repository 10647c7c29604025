// Run comparison: a baseline drawn from the same distributions is not
// flagged, a baseline that is clearly better makes this run "worse".
//
// Determinism: the fixture's seeds are fixed, so each test always sees the
// same numbers. The effect sizes are chosen far from the k = 3 threshold:
// the regressed run's intercept is 10 mm larger than its baseline's, against
// a standard error of the difference of per-position mean |errors| of about
// 0.3 mm even for Welch (z ~ 30; paired by plan index it is far smaller);
// its reprojection error is 0.5 px larger against a standard error of
// ~0.01 px (z ~ 50). For the same-distribution pair each compared figure's z
// is about N(0, 1), and a regression needs |z| beyond the Bonferroni-raised
// threshold (family-wise 0.27 %), which these seeds do not reach.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include "db/report/report.hpp"
#include "db/stats/compare.hpp"
#include "db/stats/error.hpp"
#include "store_fixture.hpp"
#include "synthetic_run.hpp"

namespace {

using rig_test::SyntheticRunSpec;

SyntheticRunSpec base_spec(std::uint64_t seed) {
  SyntheticRunSpec spec;
  spec.seed = seed;
  spec.positions = 150;
  spec.solvers = rig_test::paper_like_solvers();
  return spec;
}

TEST(ReportCompare, SameDistributionIsNotFlagged) {
  db_test::ScratchDir dir;
  rig_test::write_synthetic_run(dir.file("a.db"), base_spec(11));
  rig_test::write_synthetic_run(dir.file("b.db"), base_spec(12));
  const db::report::Report report(dir.file("a.db"), db::report::ReportOptions{},
                                  db::report::RunReference::parse(dir.file("b.db")));
  ASSERT_FALSE(report.comparison().empty());
  std::size_t paired = 0;
  for (const db::report::ComparedFigure& f : report.comparison()) {
    EXPECT_FALSE(f.worse) << f.solver << " " << f.scope << " " << f.figure << " z "
                          << f.difference.z;
    paired += f.figure.find("paired over") != std::string::npos ? 1 : 0;
  }
  EXPECT_FALSE(report.regressed());
  EXPECT_GT(paired, 0u);  // same plan: the per-position errors are compared position by position
}

// The regression threshold is k raised by Bonferroni over the counted
// figures, each under its own distribution: m * P(|T_dof| > regression_k) =
// P(|z| > k), with T_dof Student's t for a paired mean over n positions
// (dof n - 1) or a Welch mean, the normal for asymptotic figures.
TEST(ReportCompare, RegressionThresholdIsBonferroniCorrected) {
  db_test::ScratchDir dir;
  rig_test::write_synthetic_run(dir.file("a.db"), base_spec(31));
  rig_test::write_synthetic_run(dir.file("b.db"), base_spec(32));
  const db::report::Report report(dir.file("a.db"), db::report::ReportOptions{},
                                  db::report::RunReference::parse(dir.file("b.db")));
  std::size_t m = 0;
  for (const db::report::ComparedFigure& f : report.comparison())
    m += f.counted ? 1 : 0;
  ASSERT_GT(m, 10u);
  const double inf = std::numeric_limits<double>::infinity();
  std::size_t paired = 0;
  for (const db::report::ComparedFigure& f : report.comparison()) {
    const double dof = f.difference.dof;
    EXPECT_GT(f.regression_k, 3.0) << f.figure;
    // The threshold's tail is the family's share (bisection: 1e-12 relative in k).
    EXPECT_NEAR(
        m * db::stats::two_sided_tail(f.regression_k, dof) / db::stats::two_sided_tail(3.0, inf),
        1.0, 1e-9)
        << f.figure;
    if (f.figure.find("paired over") != std::string::npos) {
      ++paired;
      // A t threshold is above the normal one for the same tail.
      const double normal_k = db::stats::two_sided_threshold(
          db::stats::two_sided_tail(3.0, inf) / static_cast<double>(m), inf);
      EXPECT_GT(f.regression_k, normal_k) << f.figure;
      EXPECT_TRUE(std::isfinite(dof)) << f.figure;
    }
  }
  EXPECT_GT(paired, 0u);
}

TEST(ReportCompare, ASolverThatGotWorseIsFlaggedAndOnlyIt) {
  db_test::ScratchDir dir;
  SyntheticRunSpec worse = base_spec(21);
  for (auto& s : worse.solvers) {
    if (s.name != "hybrid_oi") continue;
    s.intercept_m += 0.010;
    s.reprojection_mean_px += 0.5;
  }
  rig_test::write_synthetic_run(dir.file("candidate.db"), worse);
  const std::int64_t baseline_run =
      rig_test::write_synthetic_run(dir.file("baseline.db"), base_spec(22)).run_id;
  const db::report::Report report(dir.file("candidate.db"), db::report::ReportOptions{},
                                  db::report::RunReference::parse(dir.file("baseline.db") + ":" +
                                                                  std::to_string(baseline_run)));
  EXPECT_TRUE(report.regressed());
  bool distance = false, reprojection = false;
  for (const db::report::ComparedFigure& f : report.comparison()) {
    if (f.solver != "hybrid_oi") {
      EXPECT_FALSE(f.worse) << f.solver << " " << f.figure;
      continue;
    }
    if (f.figure.find("distance error") != std::string::npos) {
      distance |= f.worse;
      EXPECT_GT(f.difference.z, 10.0);
    }
    if (f.figure.find("reprojection") != std::string::npos) reprojection |= f.worse;
  }
  EXPECT_TRUE(distance);
  EXPECT_TRUE(reprojection);
}

// A solver whose error grows steeply with distance (5 % of it) and scatters
// little, in two runs of different plans: the baseline's positions are the
// candidate's moved 10 mm closer. Paired by plan index, every pair would
// differ by 0.05 * 10 mm = 0.5 mm against a standard error of the mean pair
// difference of 0.5 mm * sqrt(2/3) / sqrt(150) = 0.033 mm (z ~ 15, "worse"),
// though the solver did not change. Welch on the per-position means sees the
// spread of the errors over the 0.86 m range, 0.05 * 0.86 / sqrt(12) = 12 mm,
// so its standard error is 12 mm * sqrt(2/150) = 1.4 mm and z ~ 0.35.
SyntheticRunSpec steep_spec(std::uint64_t seed, double shift_m) {
  SyntheticRunSpec spec;
  spec.seed = seed;
  spec.positions = 150;
  spec.min_distance_m = 0.12 - shift_m;
  spec.max_distance_m = 0.98 - shift_m;
  rig_test::SyntheticSolver steep;
  steep.name = "steep";
  steep.slope = 1.05;
  steep.intercept_m = 0.0;
  steep.frame_sd_m = 0.0005;
  spec.solvers = {steep};
  return spec;
}

TEST(ReportCompare, BaselineOfAnotherPlanIsComparedByWelchNotPaired) {
  db_test::ScratchDir dir;
  rig_test::write_synthetic_run(dir.file("a.db"), steep_spec(41, 0.0));
  rig_test::write_synthetic_run(dir.file("b.db"), steep_spec(42, 0.010));
  const db::report::Report report(dir.file("a.db"), db::report::ReportOptions{},
                                  db::report::RunReference::parse(dir.file("b.db")));
  ASSERT_TRUE(report.baseline().has_value());
  EXPECT_FALSE(db::report::same_plan_of(report.study(), *report.baseline()));
  std::size_t welch = 0;
  for (const db::report::ComparedFigure& f : report.comparison()) {
    EXPECT_EQ(f.figure.find("paired over"), std::string::npos) << f.figure;
    EXPECT_FALSE(f.worse) << f.solver << " " << f.scope << " " << f.figure << " z "
                          << f.difference.z;
    welch += f.figure.find("Welch (the runs' plans differ") != std::string::npos ? 1 : 0;
  }
  // Distance and reprojection error on both scopes, generalization on "0".
  EXPECT_EQ(welch, 5u);
  EXPECT_FALSE(report.regressed());

  const db::report::ReportFiles files = report.write(dir.file("out"));
  std::ifstream html(files.html);
  const std::string page((std::istreambuf_iterator<char>(html)), std::istreambuf_iterator<char>());
  EXPECT_NE(page.find("ran different plans"), std::string::npos);
}

// The Welch fallback compares the two runs' per-position means as
// independent samples: se^2 = s1^2/n1 + s2^2/n2 and z = difference / se, from
// the studies' own per-position summaries (1e-12 relative: the same doubles
// through a few operations).
TEST(ReportCompare, WelchFallbackUsesThePerPositionSummaries) {
  db_test::ScratchDir dir;
  rig_test::write_synthetic_run(dir.file("a.db"), steep_spec(43, 0.0));
  rig_test::write_synthetic_run(dir.file("b.db"), steep_spec(44, 0.050));
  const db::report::Report report(dir.file("a.db"), db::report::ReportOptions{},
                                  db::report::RunReference::parse(dir.file("b.db")));
  const db::report::SolverStudy* c = report.study().find("steep", "0");
  const db::report::SolverStudy* b = report.baseline()->find("steep", "0");
  ASSERT_NE(c, nullptr);
  ASSERT_NE(b, nullptr);
  const db::report::ComparedFigure* distance = nullptr;
  for (const db::report::ComparedFigure& f : report.comparison()) {
    if (f.scope == "0" && f.figure.find("distance error") != std::string::npos) distance = &f;
  }
  ASSERT_NE(distance, nullptr);
  const db::stats::Summary& cs = c->position_abs_error_m;
  const db::stats::Summary& bs = b->position_abs_error_m;
  EXPECT_EQ(cs.count, 150u);
  EXPECT_DOUBLE_EQ(distance->candidate, cs.mean);
  EXPECT_DOUBLE_EQ(distance->baseline, bs.mean);
  const double se = std::sqrt(cs.variance / static_cast<double>(cs.count) +
                              bs.variance / static_cast<double>(bs.count));
  EXPECT_NEAR(distance->difference.standard_error, se, 1e-12 * se);
  EXPECT_NEAR(distance->difference.z, (cs.mean - bs.mean) / se, 1e-9);
  EXPECT_TRUE(distance->counted);
}

TEST(ReportCompare, RefusesANonPositiveThreshold) {
  const db::report::RunStudy empty;
  EXPECT_THROW(db::report::compare_runs(empty, empty, 0.0), db::stats::StatsError);
  EXPECT_THROW(db::report::compare_runs(empty, empty, -3.0), db::stats::StatsError);
  EXPECT_NO_THROW(db::report::compare_runs(empty, empty, 3.0));
}

TEST(ReportCompare, ParsesTheBaselineReference) {
  const db::report::RunReference plain = db::report::RunReference::parse("runs/main.db");
  EXPECT_EQ(plain.database, "runs/main.db");
  EXPECT_FALSE(plain.run_id.has_value());
  const db::report::RunReference with_run = db::report::RunReference::parse("runs/main.db:12");
  EXPECT_EQ(with_run.database, "runs/main.db");
  EXPECT_EQ(with_run.run_id, 12);
  // A colon not followed by digits only belongs to the path.
  EXPECT_EQ(db::report::RunReference::parse("c:/runs.db").database, "c:/runs.db");
  EXPECT_THROW(db::report::RunReference::parse(":3"), db::report::ReportInputError);
}

}  // namespace
