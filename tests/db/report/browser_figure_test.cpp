// The report page in a real browser: headless Chromium loads it from a file
// with nothing else available, runs the page's own load check and must agree
// that every figure drew, with nothing on the console. The harness itself is
// checked first: it must see a console error and an uncaught exception.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>
#include <string>

#include "browser.hpp"
#include "db/report/html_page.hpp"
#include "svg_builders.hpp"

namespace {

namespace fs = std::filesystem;
using db::report::svg::Figure;
using db::report::svg::SeriesStyle;
using svg_builders::Ax;
using svg_builders::Pts;

#define SKIP_WITHOUT_CHROMIUM()        \
  if (!rig_test::chromium_available()) \
  GTEST_SKIP() << "/usr/bin/chromium is not installed (scripts/setup installs Debian's chromium)"

fs::path ArtifactDir() {
  const fs::path dir = fs::path(RIG_BINARY_DIR) / "test-artifacts";
  fs::create_directories(dir);
  return dir;
}

fs::path Write(const std::string& name, const std::string& html) {
  const fs::path path = ArtifactDir() / name;
  std::ofstream(path) << html;
  return path;
}

// The value of `data-<name>` on <body> in the dumped DOM; -1 if absent.
int BodyCount(const std::string& dom, const std::string& name) {
  const std::regex body("<body[^>]*\\bdata-" + name + "=\"([0-9]+)\"");
  std::smatch m;
  return std::regex_search(dom, m, body) ? std::stoi(m[1].str()) : -1;
}

std::string Joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines)
    out += l + "\n";
  return out;
}

std::string Plain(const std::string& script) {
  return "<!doctype html><html><head><meta "
         "charset=\"utf-8\"><title>t</title></head><body><p>x</p>" +
         script + "</body></html>";
}

TEST(BrowserHarness, ReportsConsoleErrors) {
  SKIP_WITHOUT_CHROMIUM();
  const auto r = rig_test::render_in_chromium(
      Write("console_error.html", Plain("<script>console.error(\"x-marks-the-spot\")</script>"))
          .string(),
      "");
  ASSERT_TRUE(r.ran) << r.stderr_text;
  ASSERT_EQ(r.console_errors.size(), 1u) << r.stderr_text;
  EXPECT_NE(r.console_errors[0].find("x-marks-the-spot"), std::string::npos);
}

TEST(BrowserHarness, ReportsUncaughtExceptions) {
  SKIP_WITHOUT_CHROMIUM();
  const auto r = rig_test::render_in_chromium(
      Write("exception.html", Plain("<script>throw new Error(\"boom\")</script>")).string(), "");
  ASSERT_TRUE(r.ran) << r.stderr_text;
  ASSERT_EQ(r.console_errors.size(), 1u) << r.stderr_text;
  EXPECT_NE(r.console_errors[0].find("Uncaught Error: boom"), std::string::npos);
}

TEST(BrowserHarness, CleanPageHasNoConsoleErrors) {
  SKIP_WITHOUT_CHROMIUM();
  const auto r = rig_test::render_in_chromium(
      Write("clean.html", Plain("<script>document.body.dataset.ran = 'yes'</script>")).string(),
      "");
  ASSERT_TRUE(r.ran) << r.stderr_text;
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_TRUE(r.console_errors.empty()) << Joined(r.console_errors);
  // The script ran before the DOM was dumped.
  EXPECT_NE(r.dom.find("data-ran=\"yes\""), std::string::npos) << r.dom;
}

Figure ErrorBars() {
  Figure f;
  f.id = "fig-error-bars";
  f.title = "Distance error with ±1 σ";
  f.x = Ax("true distance", "m");
  f.y = Ax("error", "mm");
  db::report::svg::Series measured = Pts("measured", {}, {});
  for (int i = 1; i <= 12; ++i) {
    measured.x.push_back(0.25 * i);
    measured.y.push_back(0.3 * std::sin(i) + 0.1 * i);
    measured.y_error.push_back(0.05 + 0.02 * i);
  }
  f.series = {measured, Pts("OLS fit", {0.25, 3.0}, {0.0, 1.2}, {}, SeriesStyle::kLine, true)};
  f.caption = "Markers: mean of 20 captures; bars: ±1 standard deviation; dashed: fit.";
  return f;
}

Figure LogLog() {
  Figure f;
  f.id = "fig-log-log";
  f.title = "Allan deviation";
  f.x = Ax("averaging time", "s", true);
  f.y = Ax("deviation", "mm", true);
  db::report::svg::Series s = Pts("x", {}, {}, {}, SeriesStyle::kLineAndMarkers);
  for (double tau = 0.01; tau < 200; tau *= 2) {
    s.x.push_back(tau);
    s.y.push_back(0.02 / std::sqrt(tau) + 1e-4 * tau);
  }
  f.series = {s};
  f.caption = "Log-log axes.";
  return f;
}

Figure Bars() {
  Figure f;
  f.id = "fig-bars";
  f.title = "Detection rate by tag size";
  f.x = Ax("tag size", "mm");
  f.y = Ax("detection rate", "%", false, 0.0, 100.0);
  f.series = {Pts("IPPE", {20, 40, 60}, {82, 96, 99}, {4, 2, 1}, SeriesStyle::kBars),
              Pts("paper", {20, 40, 60}, {80, 95, 99}, {}, SeriesStyle::kBars, true)};
  return f;
}

Figure Negative() {
  Figure f;
  f.id = "fig-residuals";
  f.title = "Residuals <x> & \"y\"";
  f.x = Ax("index", "");
  f.y = Ax("residual", "µm");
  db::report::svg::Series s = Pts("residual", {}, {});
  for (int i = 0; i < 40; ++i) {
    s.x.push_back(i);
    s.y.push_back(std::sin(0.7 * i) * 3);
  }
  f.series = {s};
  return f;
}

TEST(BrowserFigures, EveryFigureRendersWithoutConsoleErrors) {
  SKIP_WITHOUT_CHROMIUM();
  db::report::html::Page page("Figure check");
  page.begin_section("figures", "Figures");
  for (const Figure& f : {ErrorBars(), LogLog(), Bars(), Negative()})
    page.figure(f);
  page.table({"tab",
              "A table",
              {"solver", "error (mm)"},
              {{{"IPPE", "", ""}, {"0.12", "num better", ""}}}});
  page.end_section();
  const fs::path html = Write("figures.html", page.str());
  const fs::path png = ArtifactDir() / "figures.png";
  const auto r = rig_test::render_in_chromium(html.string(), png.string());
  ASSERT_TRUE(r.ran) << r.stderr_text;
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_TRUE(r.console_errors.empty()) << Joined(r.console_errors);
  EXPECT_EQ(BodyCount(r.dom, "figures-expected"), 4);
  EXPECT_EQ(BodyCount(r.dom, "figures-total"), 4) << "the load check did not run";
  EXPECT_EQ(BodyCount(r.dom, "figures-rendered"), 4);
  EXPECT_EQ(BodyCount(r.dom, "figures-empty"), 0);
  ASSERT_TRUE(r.screenshot_written) << r.stderr_text;
  EXPECT_GT(fs::file_size(png), 10000u) << "a 1280 px wide page with 4 figures";
  std::cout << "screenshot: " << png.string() << "\n";
}

TEST(BrowserFigures, LoadCheckCountsAFigureWithoutDataAsNotRendered) {
  SKIP_WITHOUT_CHROMIUM();
  db::report::html::Page page("Empty figure");
  page.figure(ErrorBars());
  Figure empty;
  empty.id = "fig-empty";
  empty.x = Ax("x", "s");
  empty.y = Ax("y", "m");
  empty.series = {Pts("nothing", {NAN}, {1})};
  page.figure(empty);
  const auto r = rig_test::render_in_chromium(Write("figure_empty.html", page.str()).string(), "");
  ASSERT_TRUE(r.ran) << r.stderr_text;
  EXPECT_EQ(BodyCount(r.dom, "figures-total"), 2);
  EXPECT_EQ(BodyCount(r.dom, "figures-rendered"), 1);
  EXPECT_EQ(BodyCount(r.dom, "figures-empty"), 1);
  EXPECT_NE(r.dom.find("id=\"fig-empty\" data-rendered=\"no\""), std::string::npos);
}

TEST(BrowserFigures, PageRefusesExternalResources) {
  SKIP_WITHOUT_CHROMIUM();
  // The page escapes all it is given, so the fetching markup is put into its
  // text after the heading: the Content-Security-Policy still stops the
  // fetch, and the refusal shows on the console.
  const std::string heading = "<h1>External</h1>\n";
  std::string html = db::report::html::Page("External").str();
  const std::size_t at = html.find(heading);
  ASSERT_NE(at, std::string::npos);
  html.insert(at + heading.size(), "<img alt=\"x\" src=\"https://example.invalid/x.png\">\n");
  const auto r = rig_test::render_in_chromium(Write("external.html", html).string(), "");
  ASSERT_TRUE(r.ran) << r.stderr_text;
  ASSERT_FALSE(r.console_errors.empty()) << r.stderr_text;
  EXPECT_NE(Joined(r.console_errors).find("Content Security Policy"), std::string::npos)
      << Joined(r.console_errors);
}

}  // namespace
