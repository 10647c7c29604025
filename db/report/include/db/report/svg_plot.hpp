// db::svg: small, dependency-free SVG figures for the reports: axes with
// units, 1-2-5 ticks, grid lines, a legend, error bars, a title.
//
// Why plain SVG text and not cairo's SVG surface: cairo writes every glyph
// as an outlined path, so labels become unsearchable, uncopyable and ten
// times larger, and the page would depend on the fonts of the machine that
// wrote it. Plain <text> is small, searchable, printable and rendered with the
// reader's own font; the only cost is that text widths must be estimated for
// the layout (we use 0.6 em per character, generous for sans-serif digits).
//
// Coordinates: the SVG user unit is one CSS pixel; the origin is the top-left
// corner of the figure, y grows downwards. Within the plot area (see Layout)
// a data value v maps affinely (or affinely in log10 v on a log axis):
//   x_px = plot_left + (v - x.lo) / (x.hi - x.lo) * plot_width
//   y_px = plot_top + plot_height - (v - y.lo) / (y.hi - y.lo) * plot_height
// where [lo, hi] is the axis range after padding and rounding to ticks.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace db::report::svg {

struct Axis {
  std::string label;  // "true distance"
  std::string unit;   // "m" -> axis title "true distance (m)"; "" for none
  // log10 scale. Points with a value <= 0 on a log axis are not drawn; the
  // figure says how many in a note under the plot area.
  bool log = false;
  // Unset: from the data (including error bars; 0 for bars) with 4 % padding;
  // a linear axis also reaches the 1-2-5 ticks enclosing the data, a log axis
  // keeps the padded range unless fewer than two ticks fall in it. No data:
  // [0, 1] ([1, 10] on a log axis). Set: used exactly (ticks inside only);
  // points outside are clipped at the plot area's edge.
  std::optional<double> min, max;
};

enum class SeriesStyle {
  kMarkers,         // one marker per point; marker shape differs per series (readable in grey)
  kLine,            // a polyline through the points in the order given; broken at skipped points
  kLineAndMarkers,  // both
  kBars,            // a bar from 0 (the axis bottom on a log axis or if 0 is below it) to y;
                    // bar series share each x slot side by side
};

struct Series {
  std::string label;            // legend text; "" = no legend entry
  std::vector<double> x, y;     // data units; points with NaN/inf x or y are skipped (counted)
  std::vector<double> y_error;  // empty, or same size as y: half-length of the error bar (±), y
                                // units, >= 0; a NaN entry draws no bar for that point
  SeriesStyle style = SeriesStyle::kMarkers;
  bool dashed = false;  // e.g. a fitted line or the paper's reference values
  // "" = the palette's next colour (ten, colour-blind safe); otherwise
  // any SVG colour ("#0072B2", "black"), written escaped.
  std::string colour;
  // Marker shape: -1 = by the series' position in the figure; 0..9 = one of
  // the ten shapes (circle, square, triangle up, diamond, triangle down, open
  // circle, open square, cross, plus, open diamond), kept across figures by
  // a caller that gives each solver its own.
  int marker = -1;
  // Empty, or same size as y: half-width (±, y units, >= 0) of a shaded band
  // drawn under the series in its colour (<path class="band">), e.g. the
  // spread while y_error shows the confidence interval of the mean; broken
  // at points with a NaN entry or that are not drawn.
  std::vector<double> y_band = {};
};

struct Figure {
  // Unique in the page; becomes the <figure id> and prefixes ids inside the
  // SVG. Must be non-empty and contain only A-Z a-z 0-9 - _ . (it is used in
  // url(#...) references).
  std::string id;
  std::string title;
  Axis x, y;
  std::vector<Series> series;
  std::string caption;                  // shown under the figure (by html::Page, not in the SVG)
  int width_px = 640, height_px = 400;  // >= 200 x 150
};

// Ticks at {1, 2, 5} x 10^k covering [lo, hi]: the first tick is <= lo, the
// last >= hi, and the step is the one whose tick count is closest to
// target_count (ties: the larger step). Tick values are k * step computed so
// that decimal ticks are the nearest doubles (0.6, not 0.6000000000000001).
// lo == hi (or a span below 1e-12 of the magnitude) is widened to
// [v - 0.05 |v|, v + 0.05 |v|] ([-1, 1] for 0) first.
// Throws std::invalid_argument if lo > hi, either is not finite, or
// target_count < 2.
std::vector<double> nice_ticks(double lo, double hi, int target_count);

// Ticks of a log10 axis covering [lo, hi] (first tick <= lo, last >= hi):
// within at most two decades 1, 2 and 5 x 10^k; otherwise decades 10^k, every
// 2nd, 3rd, 5th, 10th, ... decade (the smallest such stride giving at most
// target_count + 1 ticks).
// Throws std::invalid_argument if lo <= 0, lo > hi or either is not finite.
std::vector<double> nice_log_ticks(double lo, double hi, int target_count);

// Tick label text: plain decimals with as many places as the step needs
// ("0.25", "1500", "0.0" for 0 with step 0.2) while |value| < 1e6 and the step
// needs at most 4 places; otherwise "2.5×10⁻⁹" (mantissa with the places the
// step needs at that power of ten, "0" for zero).
std::string tick_label(double value, double step);

// One axis after layout: the range and ticks in data units, and the pixel
// span it maps onto.
struct Scale {
  double lo = 0, hi = 1;  // data range shown (for a log axis: the values, not their log)
  bool log = false;
  std::vector<double> ticks;    // data units, inside [lo, hi]
  double px_lo = 0, px_hi = 1;  // pixel coordinate of lo and hi (y: px_lo > px_hi)
  // Pixel coordinate of a data value (the affine map above). Undefined for
  // v <= 0 on a log axis.
  double to_px(double v) const;
};

// Where render_svg draws: the plot area in pixels and both scales.
struct Layout {
  double width = 0, height = 0;  // the SVG's size: the figure's, or taller if the legend needs it
  double plot_left = 0, plot_top = 0, plot_width = 0, plot_height = 0;
  Scale x, y;
};

// The layout render_svg uses for this figure (ranges from the data or the
// axes' min/max, ticks, plot area after title, tick labels, axis titles and
// legend). Throws like render_svg.
Layout layout(const Figure& figure);

// One <svg> element (no XML prolog) with viewBox, axes, tick marks and labels,
// grid lines, axis titles with units, a legend (one entry per labelled
// series), error bars, title. Text escaped.
// Markup classes the tests and the page's load check rely on: every data
// mark (marker, line, bar) has class "mark"; error bars are <path
// class="error-bar">, one per drawn point with a finite y_error; legend entries
// are <g class="legend-entry">; a figure without any finite point has a
// <text class="no-data"> note and still has axes. Circle markers (the first
// series' shape) are <circle class="mark" cx cy>; other shapes are <path
// class="mark" d="M cx,cy ...">.
// Throws std::invalid_argument naming the figure id and the series when
// x/y/y_error sizes differ, a y_error is negative, the id is empty or has
// other characters than A-Z a-z 0-9 - _ ., the size is below 200 x 150, or an
// axis min >= max (or <= 0 on a log axis).
std::string render_svg(const Figure& figure);

}  // namespace db::report::svg
