// db::svg: ticks checked by hand, and the SVG of render_svg read back with a
// small XML reader: well-formed, labelled, escaped, points where the
// documented affine map puts them.
#include "db/report/svg_plot.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "svg_builders.hpp"
#include "xml_check.hpp"

namespace {

using db::report::svg::Axis;
using db::report::svg::Figure;
using db::report::svg::Series;
using db::report::svg::SeriesStyle;
using svg_builders::Ax;
using svg_builders::Pts;

// Coordinates are written with two decimals: a rounding of at most 0.005 px.
constexpr double kPxTolerance = 0.0051;

std::vector<double> Ticks(double lo, double hi, int n) {
  return db::report::svg::nice_ticks(lo, hi, n);
}

xml_check::Document Parse(const Figure& f) {
  xml_check::Document d = xml_check::parse(db::report::svg::render_svg(f));
  EXPECT_EQ(d.error, "") << "figure " << f.id;
  return d;
}

std::set<std::string> TextsOf(const std::vector<xml_check::Element>& elements) {
  std::set<std::string> out;
  for (const auto& e : elements)
    out.insert(e.text);
  return out;
}

Figure Scatter() {
  Figure f;
  f.id = "fig-scatter";
  f.title = "Distance error";
  f.x = Ax("true distance", "m");
  f.y = Ax("error", "mm");
  f.series = {
      Pts("measured", {0.5, 1.0, 1.5, 2.0}, {0.2, -0.1, 0.4, 0.3}, {0.1, 0.1, 0.2, 0.2}),
      Pts("fit", {0.5, 2.0}, {0.0, 0.35}, {}, SeriesStyle::kLine, true),
  };
  return f;
}

// --- ticks -------------------------------------------------------------------

TEST(NiceTicks, UnitRangeInFifths) {
  EXPECT_EQ(Ticks(0, 1, 6), (std::vector<double>{0, 0.2, 0.4, 0.6, 0.8, 1.0}));
}

TEST(NiceTicks, ExtendsAnUnroundRangeToTheEnclosingTicks) {
  // Step 0.1 would give 9 ticks, 0.5 three; 0.2 gives six, nearest to five.
  EXPECT_EQ(Ticks(0.13, 0.87, 5), (std::vector<double>{0, 0.2, 0.4, 0.6, 0.8, 1.0}));
}

TEST(NiceTicks, NegativeRanges) {
  EXPECT_EQ(Ticks(-7.3, -2.1, 5), (std::vector<double>{-8, -6, -4, -2}));
  EXPECT_EQ(Ticks(-1, 3, 5), (std::vector<double>{-1, 0, 1, 2, 3}));
}

TEST(NiceTicks, ZeroIsPositiveZero) {
  for (double t : Ticks(-0.3, 0.3, 5))
    if (t == 0) {
      EXPECT_FALSE(std::signbit(t));
    }
}

TEST(NiceTicks, SingleValueIsWidenedAroundIt) {
  // 3 widened by 5 % to [2.85, 3.15]; step 0.1 gives 5 ticks.
  EXPECT_EQ(Ticks(3, 3, 5), (std::vector<double>{2.8, 2.9, 3.0, 3.1, 3.2}));
  EXPECT_EQ(Ticks(0, 0, 5), (std::vector<double>{-1, -0.5, 0, 0.5, 1}));
}

TEST(NiceTicks, TinyAndHugeRanges) {
  EXPECT_EQ(Ticks(1e-9, 3e-9, 5), (std::vector<double>{1e-9, 1.5e-9, 2e-9, 2.5e-9, 3e-9}));
  EXPECT_EQ(Ticks(1e12, 5e12, 5), (std::vector<double>{1e12, 2e12, 3e12, 4e12, 5e12}));
}

TEST(NiceTicks, CoverEvenlyWithOneTwoFiveStepsForManyRanges) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> exponent(-8, 8), unit(-1, 1);
  for (int trial = 0; trial < 2000; ++trial) {
    const double scale = std::pow(10.0, exponent(rng));
    double lo = unit(rng) * scale, hi = unit(rng) * scale;
    if (lo > hi) std::swap(lo, hi);
    const int target = 2 + trial % 9;
    const std::vector<double> t = Ticks(lo, hi, target);
    ASSERT_GE(t.size(), 2u);
    EXPECT_LE(t.front(), lo);
    EXPECT_GE(t.back(), hi);
    const double step = t[1] - t[0];
    const double mantissa = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
    // 1, 2 or 5 up to the rounding of one subtraction of ticks ~ |t| / step ulps.
    EXPECT_TRUE(std::fabs(mantissa - 1) < 1e-6 || std::fabs(mantissa - 2) < 1e-6 ||
                std::fabs(mantissa - 5) < 1e-6)
        << lo << ".." << hi << " step " << step;
    for (size_t k = 1; k < t.size(); ++k)
      EXPECT_NEAR(t[k] - t[k - 1], step, 1e-9 * std::max(std::fabs(t[k]), step));
    // Nearest 1-2-5 step: the count is within a factor 2.5 of the target.
    EXPECT_LE(static_cast<double>(t.size()), 2.5 * target + 2) << lo << ".." << hi;
  }
}

TEST(NiceTicks, RejectsBadRanges) {
  EXPECT_THROW(Ticks(2, 1, 5), std::invalid_argument);
  EXPECT_THROW(Ticks(NAN, 1, 5), std::invalid_argument);
  EXPECT_THROW(Ticks(0, INFINITY, 5), std::invalid_argument);
  EXPECT_THROW(Ticks(0, 1, 1), std::invalid_argument);
}

TEST(NiceLogTicks, DecadesOverManyDecades) {
  EXPECT_EQ(db::report::svg::nice_log_ticks(1, 1000, 5), (std::vector<double>{1, 10, 100, 1000}));
  EXPECT_EQ(db::report::svg::nice_log_ticks(0.5, 99.5, 5), (std::vector<double>{0.1, 1, 10, 100}));
}

TEST(NiceLogTicks, OneTwoFiveWithinTwoDecades) {
  EXPECT_EQ(db::report::svg::nice_log_ticks(2, 30, 5), (std::vector<double>{2, 5, 10, 20, 50}));
  EXPECT_EQ(db::report::svg::nice_log_ticks(0.003, 0.04, 5),
            (std::vector<double>{0.002, 0.005, 0.01, 0.02, 0.05}));
}

TEST(NiceLogTicks, EveryThirdDecadeOverTwelveDecades) {
  // Every decade: 13 ticks, every 2nd: 7, both above 5 + 1; every 3rd: 5.
  EXPECT_EQ(db::report::svg::nice_log_ticks(1e-6, 1e6, 5),
            (std::vector<double>{1e-6, 1e-3, 1, 1e3, 1e6}));
}

TEST(NiceLogTicks, RejectsNonPositiveRanges) {
  EXPECT_THROW(db::report::svg::nice_log_ticks(0, 10, 5), std::invalid_argument);
  EXPECT_THROW(db::report::svg::nice_log_ticks(-1, 10, 5), std::invalid_argument);
  EXPECT_THROW(db::report::svg::nice_log_ticks(10, 1, 5), std::invalid_argument);
}

TEST(TickLabel, UsesThePlacesTheStepNeeds) {
  EXPECT_EQ(db::report::svg::tick_label(0.4, 0.2), "0.4");
  EXPECT_EQ(db::report::svg::tick_label(0, 0.2), "0.0");
  EXPECT_EQ(db::report::svg::tick_label(-0.0, 0.2), "0.0");
  EXPECT_EQ(db::report::svg::tick_label(0.75, 0.25), "0.75");
  EXPECT_EQ(db::report::svg::tick_label(1500, 500), "1500");
  EXPECT_EQ(db::report::svg::tick_label(-8, 2), "-8");
}

TEST(TickLabel, PowersOfTenForTinyAndHugeValues) {
  EXPECT_EQ(db::report::svg::tick_label(2.5e-9, 5e-10), "2.5×10⁻⁹");
  EXPECT_EQ(db::report::svg::tick_label(3e12, 1e12), "3×10¹²");
  EXPECT_EQ(db::report::svg::tick_label(1e-5, 1e-5), "1×10⁻⁵");
}

// --- render_svg ----------------------------------------------------------------

TEST(RenderSvg, IsOneWellFormedSvgElementWithViewBox) {
  const xml_check::Document d = Parse(Scatter());
  ASSERT_FALSE(d.elements.empty());
  EXPECT_EQ(d.elements[0].name, "svg");
  EXPECT_EQ(d.elements[0].attrs.at("viewBox"), "0 0 640 400");
}

TEST(RenderSvg, AxisTitlesCarryUnits) {
  const xml_check::Document d = Parse(Scatter());
  EXPECT_EQ(TextsOf(xml_check::find(d, "text", "x-title")),
            std::set<std::string>{"true distance (m)"});
  EXPECT_EQ(TextsOf(xml_check::find(d, "text", "y-title")), std::set<std::string>{"error (mm)"});
}

TEST(RenderSvg, AxisWithoutUnitShowsTheLabelAlone) {
  Figure f = Scatter();
  f.y.unit = "";
  f.y.label = "detection rate";
  EXPECT_EQ(TextsOf(xml_check::find(Parse(f), "text", "y-title")),
            std::set<std::string>{"detection rate"});
}

TEST(RenderSvg, TickLabelsSitUnderTheirTicks) {
  Figure f = Scatter();
  f.x.min = 0;
  f.x.max = 1;
  const db::report::svg::Layout layout = db::report::svg::layout(f);
  // 640 px wide: about seven ticks wanted; over [0, 1] that is steps of 0.2.
  EXPECT_EQ(layout.x.ticks, (std::vector<double>{0, 0.2, 0.4, 0.6, 0.8, 1.0}));
  const xml_check::Document d = Parse(f);
  std::vector<xml_check::Element> labels;
  for (const auto& e : d.elements)
    if (e.name == "text" && e.attrs.count("text-anchor") && e.attrs.at("text-anchor") == "middle" &&
        !e.attrs.count("class"))
      labels.push_back(e);
  const std::vector<std::string> expected = {"0.0", "0.2", "0.4", "0.6", "0.8", "1.0"};
  ASSERT_EQ(labels.size(), expected.size());
  for (size_t k = 0; k < labels.size(); ++k) {
    EXPECT_EQ(labels[k].text, expected[k]);
    EXPECT_NEAR(labels[k].number("x"), layout.plot_left + 0.2 * k * layout.plot_width,
                kPxTolerance);
  }
}

TEST(RenderSvg, OneLegendEntryPerLabelledSeries) {
  Figure f = Scatter();
  f.series.push_back(Pts("", {1}, {1}));  // unlabelled: no entry
  const xml_check::Document d = Parse(f);
  const auto entries = xml_check::find(d, "g", "legend-entry");
  EXPECT_EQ(entries.size(), 2u);
  std::set<std::string> texts;
  for (const auto& e : d.elements)
    if (e.name == "text" && e.depth == entries[0].depth + 1) texts.insert(e.text);
  EXPECT_EQ(texts, (std::set<std::string>{"measured", "fit"}));
}

TEST(RenderSvg, CutsALegendLabelWiderThanTheFigure) {
  Figure f = Scatter();
  std::string label;
  for (int i = 0; i < 40; ++i)
    label += "σ label ";  // 320 characters, over 2000 px at 12 px
  f.series[0].label = label;
  const xml_check::Document d = Parse(f);
  const auto entries = xml_check::find(d, "g", "legend-entry");
  ASSERT_EQ(entries.size(), 2u);
  bool cut = false;
  for (const auto& e : d.elements)
    if (e.name == "text" && e.depth == entries[0].depth + 1 && e.text.size() < label.size() &&
        e.text.compare(e.text.size() - 3, 3, "…") == 0) {
      cut = true;
      EXPECT_EQ(label.compare(0, e.text.size() - 3, e.text, 0, e.text.size() - 3), 0);
    }
  EXPECT_TRUE(cut);
  EXPECT_EQ(TextsOf(xml_check::find(d, "title")).count(label), 1u) << "full label as tooltip";
}

TEST(RenderSvg, OneErrorBarPerDrawnPointWithAFiniteError) {
  Figure f;
  f.id = "errors";
  f.x = Ax("x", "");
  f.y = Ax("y", "");
  // 5 points: one has no error (NaN), one is not drawn (y NaN): 3 bars.
  f.series = {Pts("s", {1, 2, 3, 4, 5}, {1, 2, NAN, 4, 5}, {0.5, NAN, 0.5, 0.5, 0.0})};
  EXPECT_EQ(xml_check::find(Parse(f), "path", "error-bar").size(), 3u);
}

TEST(RenderSvg, ErrorBarSpansYPlusMinusError) {
  Figure f;
  f.id = "bar";
  f.x = Ax("x", "", false, 0.0, 10.0);
  f.y = Ax("y", "", false, 0.0, 10.0);
  f.series = {Pts("s", {5}, {4}, {2})};
  const db::report::svg::Layout l = db::report::svg::layout(f);
  const auto bars = xml_check::find(Parse(f), "path", "error-bar");
  ASSERT_EQ(bars.size(), 1u);
  // "M x,y_lo V y_hi ...": from y - e = 2 to y + e = 6.
  double x = 0, y_lo = 0, y_hi = 0;
  ASSERT_EQ(std::sscanf(bars[0].attrs.at("d").c_str(), "M%lf,%lf V%lf", &x, &y_lo, &y_hi), 3);
  const double bottom = l.plot_top + l.plot_height;
  EXPECT_NEAR(y_lo, bottom - 0.2 * l.plot_height, kPxTolerance);
  EXPECT_NEAR(y_hi, bottom - 0.6 * l.plot_height, kPxTolerance);
  EXPECT_NEAR(x, l.plot_left + 0.5 * l.plot_width, kPxTolerance);
}

TEST(RenderSvg, MapsAPointAffinelyIntoThePlotArea) {
  Figure f;
  f.id = "map";
  f.x = Ax("x", "m", false, 0.0, 10.0);
  f.y = Ax("y", "m", false, -1.0, 1.0);
  f.series = {Pts("s", {2.5}, {0.5})};
  const db::report::svg::Layout l = db::report::svg::layout(f);
  const xml_check::Document d = Parse(f);
  const auto marks = xml_check::find(d, "circle", "mark");
  ASSERT_EQ(marks.size(), 1u);
  // x: a quarter of the way across; y: three quarters of the way up.
  EXPECT_NEAR(marks[0].number("cx"), l.plot_left + 0.25 * l.plot_width, kPxTolerance);
  EXPECT_NEAR(marks[0].number("cy"), l.plot_top + 0.25 * l.plot_height, kPxTolerance);
  // The clip rectangle is the plot area the map refers to.
  const auto clip = xml_check::find(d, "clipPath");
  ASSERT_EQ(clip.size(), 1u);
  const auto rects = xml_check::find(d, "rect");
  bool found = false;
  for (const auto& r : rects)
    if (r.depth == clip[0].depth + 1) {
      found = true;
      EXPECT_NEAR(r.number("x"), l.plot_left, kPxTolerance);
      EXPECT_NEAR(r.number("y"), l.plot_top, kPxTolerance);
      EXPECT_NEAR(r.number("width"), l.plot_width, kPxTolerance);
      EXPECT_NEAR(r.number("height"), l.plot_height, kPxTolerance);
    }
  EXPECT_TRUE(found);
}

TEST(RenderSvg, MapsLogAxesInDecades) {
  Figure f;
  f.id = "log";
  f.x = Ax("frequency", "Hz", true, 1.0, 1000.0);
  f.y = Ax("power", "W", true, 1e-3, 1.0);
  f.series = {Pts("s", {10}, {0.1})};
  const db::report::svg::Layout l = db::report::svg::layout(f);
  const auto marks = xml_check::find(Parse(f), "circle", "mark");
  ASSERT_EQ(marks.size(), 1u);
  // 10 is one decade of three along x; 0.1 two decades of three up y.
  EXPECT_NEAR(marks[0].number("cx"), l.plot_left + l.plot_width / 3, kPxTolerance);
  EXPECT_NEAR(marks[0].number("cy"), l.plot_top + l.plot_height / 3, kPxTolerance);
  EXPECT_EQ(l.x.ticks, (std::vector<double>{1, 10, 100, 1000}));
}

TEST(RenderSvg, CountsPointsALogAxisCannotShow) {
  Figure f;
  f.id = "logskip";
  f.x = Ax("x", "", false);
  f.y = Ax("y", "", true);
  f.series = {Pts("s", {1, 2, 3, 4}, {1, 0, -2, 10}), Pts("t", {1, NAN}, {1, 1})};
  const xml_check::Document d = Parse(f);
  EXPECT_EQ(xml_check::find(d, "", "mark").size(), 3u);
  EXPECT_EQ(TextsOf(xml_check::find(d, "text", "note")),
            std::set<std::string>{
                "1 point not shown: not finite. 2 points not shown: ≤ 0 on a log axis."});
}

TEST(RenderSvg, EscapesMarkupInEveryText) {
  const std::string nasty = "a<b & \"c\" 'd'>";
  Figure f = Scatter();
  f.title = nasty;
  f.x.label = nasty;
  f.series[0].label = nasty;
  const std::string svg = db::report::svg::render_svg(f);
  EXPECT_EQ(svg.find(nasty), std::string::npos);
  const xml_check::Document d = xml_check::parse(svg);
  ASSERT_EQ(d.error, "");
  EXPECT_EQ(TextsOf(xml_check::find(d, "text", "title")), std::set<std::string>{nasty});
  EXPECT_EQ(TextsOf(xml_check::find(d, "text", "x-title")), std::set<std::string>{nasty + " (m)"});
  EXPECT_EQ(TextsOf(xml_check::find(d, "title")), std::set<std::string>{nasty});
}

TEST(RenderSvg, SizeMismatchNamesFigureAndSeries) {
  Figure f = Scatter();
  f.series[1].y.push_back(1);
  try {
    db::report::svg::render_svg(f);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("figure 'fig-scatter' series 1 ('fit')"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("2 x values but 3 y values"), std::string::npos)
        << e.what();
  }
  f = Scatter();
  f.series[0].y_error.pop_back();
  EXPECT_THROW(
      {
        try {
          db::report::svg::render_svg(f);
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("3 y_error values for 4 points"), std::string::npos)
              << e.what();
          throw;
        }
      },
      std::invalid_argument);
}

TEST(RenderSvg, RejectsIdsThatCannotBeReferenced) {
  Figure f = Scatter();
  f.id = "two words";
  EXPECT_THROW(db::report::svg::render_svg(f), std::invalid_argument);
  f.id = "";
  EXPECT_THROW(db::report::svg::render_svg(f), std::invalid_argument);
}

TEST(RenderSvg, RejectsNegativeErrorsAndEmptyAxisRanges) {
  Figure f = Scatter();
  f.series[0].y_error[2] = -0.1;
  EXPECT_THROW(db::report::svg::render_svg(f), std::invalid_argument);
  f = Scatter();
  f.x.min = 2;
  f.x.max = 2;
  EXPECT_THROW(db::report::svg::render_svg(f), std::invalid_argument);
  f = Scatter();
  f.x.log = true;
  f.x.min = 0;
  EXPECT_THROW(db::report::svg::render_svg(f), std::invalid_argument);
}

TEST(RenderSvg, FigureWithoutDataStillHasAxesAndSaysSo) {
  Figure f;
  f.id = "empty";
  f.title = "Nothing measured";
  f.x = Ax("x", "s");
  f.y = Ax("y", "m");
  f.series = {Pts("s", {NAN, 1}, {1, INFINITY})};
  const xml_check::Document d = Parse(f);
  EXPECT_EQ(TextsOf(xml_check::find(d, "text", "no-data")), std::set<std::string>{"no data"});
  EXPECT_EQ(xml_check::find(d, "", "mark").size(), 0u);
  EXPECT_EQ(xml_check::find(d, "path", "ticks").size(), 1u);
  EXPECT_EQ(TextsOf(xml_check::find(d, "text", "x-title")), std::set<std::string>{"x (s)"});
  // A figure with no series at all is drawn the same way.
  f.series.clear();
  EXPECT_EQ(xml_check::find(Parse(f), "text", "no-data").size(), 1u);
}

TEST(RenderSvg, LinesBreakAtSkippedPoints) {
  Figure f;
  f.id = "gap";
  f.series = {Pts("s", {1, 2, 3, 4, 5}, {1, 2, NAN, 4, 5}, {}, SeriesStyle::kLine)};
  const auto lines = xml_check::find(Parse(f), "polyline", "line");
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(std::count(lines[0].attrs.at("points").begin(), lines[0].attrs.at("points").end(), ','),
            2);
}

TEST(RenderSvg, BarsRiseFromZero) {
  Figure f;
  f.id = "bars";
  f.x = Ax("size", "mm");
  f.y = Ax("rate", "%", false, std::nullopt, 100.0);
  f.series = {Pts("a", {10, 20}, {50, 80}, {}, SeriesStyle::kBars),
              Pts("b", {10, 20}, {40, 90}, {}, SeriesStyle::kBars)};
  const db::report::svg::Layout l = db::report::svg::layout(f);
  EXPECT_EQ(l.y.lo, 0);  // bars include 0 and 0 is not padded
  const auto bars = xml_check::find(Parse(f), "rect", "bar");
  ASSERT_EQ(bars.size(), 4u);
  const double zero_px = l.plot_top + l.plot_height;
  for (const auto& b : bars)
    EXPECT_NEAR(b.number("y") + b.number("height"), zero_px, 2 * kPxTolerance);
  // Side by side in one slot: the two bars at x = 10 touch and do not overlap.
  EXPECT_NEAR(bars[0].number("x") + bars[0].number("width"), bars[2].number("x"), 2 * kPxTolerance);
}

TEST(RenderSvg, PaletteColoursDifferAndExplicitColoursAreKept) {
  Figure f;
  f.id = "colours";
  for (int i = 0; i < 3; ++i)
    f.series.push_back(Pts("s" + std::to_string(i), {1.0 * i}, {1.0 * i}));
  f.series[1].colour = "rebeccapurple";
  std::set<std::string> fills;
  for (const auto& m : xml_check::find(Parse(f), "", "mark"))
    fills.insert(m.attrs.at("fill"));
  EXPECT_EQ(fills.size(), 3u);
  EXPECT_EQ(fills.count("rebeccapurple"), 1u);
}

}  // namespace
