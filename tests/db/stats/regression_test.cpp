// Least-squares lines against the NIST StRD certified values (Norris: a line
// with intercept; NoInt1: a line through the origin). The certified values are
// read from the dataset files' headers, not retyped here.
#include "db/stats/regression.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "db/stats/error.hpp"

namespace {

using db::stats::LineFit;

// A NIST StRD file as kept in tests/data/nist (tests/data/README.md says where each comes from):
// '#' header lines with "NAME = value" certified figures, then "y x" rows.
struct NistDataset {
  std::vector<double> x, y;
  std::map<std::string, double> certified;  // "B0", "sd(B0)", "B1", "sd(B1)", "residual sd", ...
};

NistDataset load_nist(const std::string& name) {
  const std::string path = std::string(RIG_SOURCE_DIR) + "/tests/data/nist/" + name + ".txt";
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  NistDataset d;
  const std::regex number_after(R"(([A-Za-z0-9()\- ]+?)\s*=\s*([-+0-9.Ee]+))");
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (line[0] == '#') {
      for (auto it = std::sregex_iterator(line.begin(), line.end(), number_after);
           it != std::sregex_iterator(); ++it) {
        std::string key = (*it)[1].str();
        key = std::regex_replace(key, std::regex(R"(^\s+|\s+$)"), "");
        d.certified[key] = std::stod((*it)[2].str());
      }
      continue;
    }
    std::istringstream row(line);
    double y = 0, x = 0;
    if (row >> y >> x) {
      d.y.push_back(y);
      d.x.push_back(x);
    }
  }
  return d;
}

double certified(const NistDataset& d, const std::string& key) {
  const auto it = d.certified.find(key);
  if (it == d.certified.end()) throw std::runtime_error("no certified value '" + key + "'");
  return it->second;
}

// The fits must match to 1e-9 relative; the certified values carry 15 significant
// digits and a centred two-pass fit loses only a few bits on these
// (low/average difficulty) datasets, so 1e-9 leaves a wide margin.
constexpr double kRelative = 1e-9;

void expect_relative(double actual, double expected, const char* what) {
  EXPECT_NEAR(actual, expected, kRelative * std::abs(expected)) << what;
}

TEST(NistNorris, HeaderHoldsTheCertifiedFiguresAndThe36Rows) {
  const NistDataset d = load_nist("Norris");
  EXPECT_EQ(d.x.size(), 36u);
  for (const char* key : {"B0", "sd(B0)", "B1", "sd(B1)", "residual standard deviation",
                          "R-squared", "residual sum of squares"}) {
    EXPECT_EQ(d.certified.count(key), 1u) << key;
  }
}

TEST(FitLine, MatchesNistNorrisCoefficientsAndStandardDeviations) {
  const NistDataset d = load_nist("Norris");
  const LineFit fit = db::stats::fit_line(d.x, d.y);
  expect_relative(fit.intercept, certified(d, "B0"), "B0");
  expect_relative(fit.intercept_se, certified(d, "sd(B0)"), "sd(B0)");
  expect_relative(fit.slope, certified(d, "B1"), "B1");
  expect_relative(fit.slope_se, certified(d, "sd(B1)"), "sd(B1)");
}

TEST(FitLine, MatchesNistNorrisResidualStandardDeviationAndRSquared) {
  const NistDataset d = load_nist("Norris");
  const LineFit fit = db::stats::fit_line(d.x, d.y);
  EXPECT_EQ(fit.dof, 34u);
  expect_relative(fit.residual_sd, certified(d, "residual standard deviation"), "residual sd");
  expect_relative(fit.residual_sum_of_squares, certified(d, "residual sum of squares"), "SSR");
  expect_relative(fit.r_squared, certified(d, "R-squared"), "R^2");
  // Paper Table 5 convention: variance of residuals = RMS^2 = SSR / dof.
  expect_relative(fit.residual_variance, fit.residual_sd * fit.residual_sd, "variance");
  expect_relative(fit.residual_rms, std::sqrt(fit.residual_sum_of_squares / 36.0), "rms");
}

TEST(FitLineThroughOrigin, MatchesNistNoInt1SlopeAndStandardDeviation) {
  const NistDataset d = load_nist("NoInt1");
  ASSERT_EQ(d.x.size(), 11u);
  const LineFit fit = db::stats::fit_line_through_origin(d.x, d.y);
  expect_relative(fit.slope, certified(d, "B1"), "B1");
  expect_relative(fit.slope_se, certified(d, "sd(B1)"), "sd(B1)");
  EXPECT_EQ(fit.intercept, 0.0);
}

TEST(FitLineThroughOrigin, MatchesNistNoInt1ResidualStandardDeviationAndUncentredRSquared) {
  const NistDataset d = load_nist("NoInt1");
  const LineFit fit = db::stats::fit_line_through_origin(d.x, d.y);
  EXPECT_EQ(fit.dof, 10u);
  expect_relative(fit.residual_sd, certified(d, "residual standard deviation"), "residual sd");
  expect_relative(fit.residual_sum_of_squares, certified(d, "residual sum of squares"), "SSR");
  expect_relative(fit.r_squared, certified(d, "R-squared"), "R^2");
}

TEST(FitLine, KeepsNorrisAccuracyWhenXIsShiftedFarFromZero) {
  // Adding 1e6 to every x moves only the intercept (b' = b - a 1e6); a naive
  // sum-of-squares formula loses ~12 digits here, the centred fit does not.
  NistDataset d = load_nist("Norris");
  for (double& x : d.x)
    x += 1e6;
  const LineFit fit = db::stats::fit_line(d.x, d.y);
  expect_relative(fit.slope, certified(d, "B1"), "B1");
  expect_relative(fit.slope_se, certified(d, "sd(B1)"), "sd(B1)");
  expect_relative(fit.residual_sd, certified(d, "residual standard deviation"), "residual sd");
}

TEST(FitLineWeighted, EqualSigmasGiveOlsCoefficientsAndSigmaScaledErrors) {
  // With every sigma_y = s the weighted fit is OLS; its standard errors are
  // those of the stated s, i.e. OLS's scaled by s / residual_sd.
  const NistDataset d = load_nist("Norris");
  const double s = 2.0;
  const LineFit ols = db::stats::fit_line(d.x, d.y);
  const LineFit w = db::stats::fit_line_weighted(d.x, d.y, std::vector<double>(d.x.size(), s));
  expect_relative(w.slope, ols.slope, "slope");
  expect_relative(w.intercept, ols.intercept, "intercept");
  expect_relative(w.slope_se, ols.slope_se * s / ols.residual_sd, "slope se");
  expect_relative(w.intercept_se, ols.intercept_se * s / ols.residual_sd, "intercept se");
  expect_relative(w.residual_sum_of_squares, ols.residual_sum_of_squares / (s * s), "chi^2");
  expect_relative(w.r_squared, ols.r_squared, "R^2");
}

TEST(FitLine, RejectsMismatchedLengths) {
  EXPECT_THROW(db::stats::fit_line({1, 2, 3}, {1, 2}), db::stats::StatsError);
}

TEST(FitLine, RejectsAllEqualX) {
  EXPECT_THROW(db::stats::fit_line({2, 2, 2}, {1, 2, 3}), db::stats::StatsError);
}

TEST(FitLine, RejectsTwoPointsBecauseNoResidualDegreeOfFreedomRemains) {
  EXPECT_THROW(db::stats::fit_line({1, 2}, {1, 2}), db::stats::StatsError);
}

}  // namespace
