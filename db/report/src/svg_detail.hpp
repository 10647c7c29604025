// Internals shared by the layout (svg_plot.cpp) and the drawing
// (svg_render.cpp) of db::svg figures. Not a public header.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "db/report/svg_plot.hpp"

namespace db::report::svg::detail {

// Ten colours for ten solvers: Okabe & Ito (2008), "Color Universal
// Design", distinguishable with every common colour-vision deficiency, and
// two of Paul Tol's muted scheme (wine #882255, olive #999933) that stay
// apart from them under the same deficiencies. Yellow (#F0E442) last: faint
// on white.
inline constexpr const char* kPalette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00",
                                           "#56B4E9", "#000000", "#882255", "#999933", "#F0E442"};
inline constexpr int kPaletteSize = sizeof kPalette / sizeof kPalette[0];

// Type sizes (px) and the width estimate of one character: 0.6 em covers
// digits and most letters of a sans-serif font; the layout leaves that room.
inline constexpr double kTickFont = 11, kTitleFont = 14, kAxisFont = 12, kLegendFont = 12;
inline constexpr double kNoteFont = 11;
inline constexpr double kCharEm = 0.6;
inline constexpr double kTickLength = 5;
inline constexpr double kMarkerRadius = 3.5;
inline constexpr double kLegendRow = 18;
inline constexpr double kLegendSample = 24;  // width of the line/marker sample in an entry

// A value for an error message, to 17 significant digits (it reads back
// exactly).
std::string number(double v);
// Text for XML content or a quoted attribute; control characters XML 1.0
// forbids become spaces.
std::string escape(std::string_view text);
// Pixel coordinate with at most two decimals, trailing zeros dropped.
std::string px(double v);
double text_width(std::string_view text, double font_px);
// `text` cut to at most `width` px (estimated) at a UTF-8 character boundary,
// ending in "…" if cut.
std::string fit_text(const std::string& text, double width, double font_px);
std::string axis_title(const Axis& axis);
// x and y finite, and > 0 on a log axis.
bool drawable(const Figure& f, double x, double y);
std::vector<std::string> tick_labels(const Scale& s);
// "2 points not shown: not finite." etc.; "" if every point is drawn.
std::string notes_text(const Figure& f);
size_t drawn_point_count(const Figure& f);

struct LegendItem {
  size_t series;
  double x, y;       // left and top of the entry, relative to the legend's origin
  std::string text;  // the label, cut with "…" if it is wider than the figure
};
// Entries of the labelled series flowing left to right, wrapped to `width`.
std::vector<LegendItem> legend_items(const Figure& f, double width, int* rows);

// What sits under the plot area, as baselines/tops in px below its bottom
// edge; one function so the layout and the drawing agree.
struct BelowPlot {
  double tick_label = 0;  // x tick label baseline
  double x_title = 0;     // x axis title baseline (if there is a title)
  double legend_top = 0;  // top of the first legend row (if there are entries)
  double note = 0;        // baseline of the skipped-points note (if any)
  double total = 0;       // height needed under the plot area
};
BelowPlot below_plot(const Figure& f, int legend_rows);

}  // namespace db::report::svg::detail
