// report.html in a real browser: headless Chromium loads it
// with no console message, every figure is drawn with data marks, and a
// screenshot is left in <build>/test-artifacts/report.png for a person.
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>
#include <set>

#include "browser.hpp"
#include "db/report/report.hpp"
#include "store_fixture.hpp"
#include "synthetic_run.hpp"
#include "vision/image_codecs.hpp"

namespace {

int body_attribute(const std::string& dom, const std::string& name) {
  const std::regex re(name + "=\"([0-9]+)\"");
  std::smatch m;
  if (!std::regex_search(dom, m, re)) return -1;
  return std::stoi(m[1]);
}

TEST(ReportBrowser, RendersEveryFigureWithoutConsoleErrors) {
  if (!rig_test::chromium_available()) GTEST_SKIP() << "no /usr/bin/chromium";
  db_test::ScratchDir dir;
  rig_test::SyntheticRunSpec spec;
  spec.positions = 60;
  spec.solvers = rig_test::paper_like_solvers();
  rig_test::write_synthetic_run(dir.file("run.db"), spec);
  spec.seed = 5;
  rig_test::write_synthetic_run(dir.file("baseline.db"), spec);
  const db::report::Report report(dir.file("run.db"), db::report::ReportOptions{},
                                  db::report::RunReference::parse(dir.file("baseline.db")));
  const db::report::ReportFiles files = report.write(dir.file("out"));

  const std::filesystem::path artifacts = std::filesystem::path(RIG_BINARY_DIR) / "test-artifacts";
  std::filesystem::create_directories(artifacts);
  const std::string png = (artifacts / "report.png").string();
  std::filesystem::remove(png);
  const rig_test::BrowserResult r = rig_test::render_in_chromium(files.html, png);
  ASSERT_TRUE(r.ran) << r.stderr_text;
  EXPECT_EQ(r.exit_code, 0) << r.stderr_text;
  EXPECT_TRUE(r.console_errors.empty()) << r.console_errors.front();
  const int expected = body_attribute(r.dom, "data-figures-expected");
  const int total = body_attribute(r.dom, "data-figures-total");
  const int rendered = body_attribute(r.dom, "data-figures-rendered");
  EXPECT_GT(total, 10);
  EXPECT_EQ(total, expected);
  EXPECT_EQ(rendered, total);
  EXPECT_EQ(body_attribute(r.dom, "data-figures-empty"), 0);
  EXPECT_TRUE(r.screenshot_written);
}

// What an engineer sees at 1400 px with the ten solvers of a sweep: nothing
// overflows sideways, the summary is the first table, every solver has its
// own colour in the figures, and the page logs nothing.
TEST(ReportBrowser, TenSolversAt1400PixelsFitWithDistinctColours) {
  if (!rig_test::chromium_available()) GTEST_SKIP() << "no /usr/bin/chromium";
  db_test::ScratchDir dir;
  rig_test::SyntheticRunSpec spec;
  spec.positions = 40;
  spec.solvers = rig_test::paper_like_solvers();
  const char* more[] = {"dls", "lm", "oi", "epnp", "opencv_iterative", "sqpnp"};
  for (int i = 0; i < 6; ++i) {
    rig_test::SyntheticSolver s;
    s.name = more[i];
    s.intercept_m = 0.0005 * (i + 1);  // distinct results: nothing coincides
    spec.solvers.push_back(s);
  }
  rig_test::write_synthetic_run(dir.file("run.db"), spec);
  db::report::Report report(dir.file("run.db"), db::report::ReportOptions{});
  // Pictures of frames as `rig report` draws them (360 x 279 px PNGs), one
  // per frame it would show.
  std::vector<db::report::FramePicture> pictures;
  for (const db::report::FrameToShow& f : report.frames_to_show()) {
    std::vector<unsigned char> png;
    ASSERT_TRUE(vision::imencode(".png", cv::Mat(279, 360, CV_8UC3, cv::Scalar(90, 90, 90)), png));
    pictures.push_back({f, std::string(png.begin(), png.end()), 360, 279, 0.49, "grey"});
  }
  ASSERT_GE(pictures.size(), 10u);
  report.set_pictures(pictures);
  const db::report::ReportFiles files = report.write(dir.file("out"));
  const rig_test::BrowserResult r = rig_test::render_in_chromium(files.html, "", 1400);
  ASSERT_TRUE(r.ran) << r.stderr_text;
  EXPECT_EQ(r.exit_code, 0) << r.stderr_text;
  EXPECT_TRUE(r.console_errors.empty()) << r.console_errors.front();
  const int viewport = body_attribute(r.dom, "data-viewport-width");
  ASSERT_GT(viewport, 1300) << "the window was not 1400 px wide";
  EXPECT_LE(body_attribute(r.dom, "data-page-width"), viewport);
  const auto first_table = r.dom.find("<table");
  ASSERT_NE(first_table, std::string::npos);
  EXPECT_EQ(r.dom.find("<table id=\"summary\">"), first_table);
  // Fig. 8 of the pose marker: one line per solver, ten colours.
  const auto fig = r.dom.find("<figure class=\"plot\" id=\"fig8-0\"");
  ASSERT_NE(fig, std::string::npos);
  const std::string svg = r.dom.substr(fig, r.dom.find("</figure>", fig) - fig);
  const std::regex line_colour("stroke=\"(#[0-9A-Fa-f]{6})\" stroke-width=\"1.8\"");
  std::set<std::string> colours;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), line_colour);
       it != std::sregex_iterator(); ++it)
    colours.insert((*it)[1]);
  EXPECT_EQ(colours.size(), 10u);
  std::size_t shown = 0;
  for (auto at = r.dom.find("<figure class=\"frame\""); at != std::string::npos;
       at = r.dom.find("<figure class=\"frame\"", at + 1))
    ++shown;
  EXPECT_EQ(shown, pictures.size());
}

}  // namespace
