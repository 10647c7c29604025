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

#include "db/report.hpp"
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
  const db::Report report(dir.file("a.db"), db::ReportOptions{},
                          db::RunReference::parse(dir.file("b.db")));
  ASSERT_FALSE(report.comparison().empty());
  std::size_t paired = 0;
  for (const db::ComparedFigure& f : report.comparison()) {
    EXPECT_FALSE(f.worse) << f.solver << " " << f.scope << " " << f.figure << " z "
                          << f.difference.z;
    paired += f.figure.find("paired over") != std::string::npos ? 1 : 0;
  }
  EXPECT_FALSE(report.regressed());
  EXPECT_GT(paired, 0u);  // same plan: the per-position errors are compared position by position
}

// The regression threshold is k raised by Bonferroni over the counted
// figures: m * P(|z| > regression_k) = P(|z| > k), two-sided normal.
TEST(ReportCompare, RegressionThresholdIsBonferroniCorrected) {
  db_test::ScratchDir dir;
  rig_test::write_synthetic_run(dir.file("a.db"), base_spec(31));
  rig_test::write_synthetic_run(dir.file("b.db"), base_spec(32));
  const db::Report report(dir.file("a.db"), db::ReportOptions{},
                          db::RunReference::parse(dir.file("b.db")));
  std::size_t m = 0;
  for (const db::ComparedFigure& f : report.comparison())
    m += f.counted ? 1 : 0;
  ASSERT_GT(m, 10u);
  const double k = report.comparison().front().regression_k;
  EXPECT_GT(k, 3.0);
  EXPECT_NEAR(m * std::erfc(k / std::sqrt(2.0)) / std::erfc(3.0 / std::sqrt(2.0)), 1.0, 1e-9);
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
  const db::Report report(
      dir.file("candidate.db"), db::ReportOptions{},
      db::RunReference::parse(dir.file("baseline.db") + ":" + std::to_string(baseline_run)));
  EXPECT_TRUE(report.regressed());
  bool distance = false, reprojection = false;
  for (const db::ComparedFigure& f : report.comparison()) {
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

TEST(ReportCompare, ParsesTheBaselineReference) {
  const db::RunReference plain = db::RunReference::parse("runs/main.db");
  EXPECT_EQ(plain.database, "runs/main.db");
  EXPECT_FALSE(plain.run_id.has_value());
  const db::RunReference with_run = db::RunReference::parse("runs/main.db:12");
  EXPECT_EQ(with_run.database, "runs/main.db");
  EXPECT_EQ(with_run.run_id, 12);
  // A colon not followed by digits only belongs to the path.
  EXPECT_EQ(db::RunReference::parse("c:/runs.db").database, "c:/runs.db");
  EXPECT_THROW(db::RunReference::parse(":3"), db::ReportInputError);
}

}  // namespace
