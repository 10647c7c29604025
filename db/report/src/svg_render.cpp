// Drawing a laid-out db::svg figure: one pass writing background, grid, data
// (clipped to the plot area), axes, tick labels, titles, legend and notes.
// Plain SVG elements with presentation attributes, so the figure looks the
// same inside the page, saved alone, or printed.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "db/report/svg_plot.hpp"
#include "svg_detail.hpp"

namespace db::report::svg {
namespace {

using namespace detail;

// circle, square, triangle up, diamond, triangle down, open circle, open
// square, cross, plus, open diamond
constexpr int kShapeCount = 10;

std::string attr(const char* name, const std::string& value) {
  return std::string(" ") + name + "=\"" + value + "\"";
}

// A marker centred on (cx, cy). Shapes differ per series so that series stay
// apart in grey print and for readers who cannot tell the colours apart.
std::string marker(int shape, double cx, double cy, const std::string& colour, const char* cls) {
  const std::string c = escape(colour);
  const std::string klass = cls[0] ? attr("class", cls) : "";
  const std::string at = "M" + px(cx) + "," + px(cy);
  const std::string paint = attr("fill", c) + attr("stroke", c);
  const std::string open =
      attr("fill", "#ffffff") + attr("stroke", c) + attr("stroke-width", "1.5");
  const std::string line = attr("fill", "none") + attr("stroke", c) + attr("stroke-width", "1.8");
  switch (shape % kShapeCount) {
    case 0:
      return "<circle" + klass + attr("cx", px(cx)) + attr("cy", px(cy)) +
             attr("r", px(kMarkerRadius)) + paint + "/>";
    case 1:
      return "<path" + klass + attr("d", at + " m-3.2,-3.2 h6.4 v6.4 h-6.4 z") + paint + "/>";
    case 2:
      return "<path" + klass + attr("d", at + " m0,-4.4 l3.9,6.6 h-7.8 z") + paint + "/>";
    case 3:
      return "<path" + klass + attr("d", at + " m0,-4.6 l4.6,4.6 l-4.6,4.6 l-4.6,-4.6 z") + paint +
             "/>";
    case 4:
      return "<path" + klass + attr("d", at + " m0,4.4 l3.9,-6.6 h-7.8 z") + paint + "/>";
    case 5:
      return "<circle" + klass + attr("cx", px(cx)) + attr("cy", px(cy)) +
             attr("r", px(kMarkerRadius)) + open + "/>";
    case 6:
      return "<path" + klass + attr("d", at + " m-3.2,-3.2 h6.4 v6.4 h-6.4 z") + open + "/>";
    case 7:
      return "<path" + klass + attr("d", at + " m-3.5,-3.5 l7,7 m0,-7 l-7,7") + line + "/>";
    case 8:
      return "<path" + klass + attr("d", at + " m-4.2,0 h8.4 m-4.2,-4.2 v8.4") + line + "/>";
    default:
      return "<path" + klass + attr("d", at + " m0,-4.6 l4.6,4.6 l-4.6,4.6 l-4.6,-4.6 z") + open +
             "/>";
  }
}

int shape_of(const Series& s, size_t index) {
  return s.marker >= 0 ? s.marker : static_cast<int>(index);
}

bool has_line(SeriesStyle s) {
  return s == SeriesStyle::kLine || s == SeriesStyle::kLineAndMarkers;
}
bool has_markers(SeriesStyle s) {
  return s == SeriesStyle::kMarkers || s == SeriesStyle::kLineAndMarkers;
}

std::string stroke_dash(const Series& s) {
  return s.dashed ? attr("stroke-dasharray", "6 4") : std::string();
}

// Bar geometry shared by all bar series: the slot (px) one x value gets, and
// how many bar series share it side by side.
struct BarSlots {
  double slot_px = 0;
  int count = 0;
};

BarSlots bar_slots(const Figure& f, const Layout& L) {
  BarSlots b;
  std::vector<double> xs;
  for (const Series& s : f.series) {
    if (s.style != SeriesStyle::kBars) continue;
    ++b.count;
    for (size_t k = 0; k < s.x.size(); ++k)
      if (drawable(f, s.x[k], s.y[k])) xs.push_back(L.x.to_px(s.x[k]));
  }
  std::sort(xs.begin(), xs.end());
  double gap = std::numeric_limits<double>::infinity();
  for (size_t k = 1; k < xs.size(); ++k)
    if (xs[k] - xs[k - 1] > 0.5) gap = std::min(gap, xs[k] - xs[k - 1]);
  if (!std::isfinite(gap)) {  // one x value: the layout gave it one axis unit (decade)
    const double unit = L.x.log ? std::log10(L.x.hi / L.x.lo) : L.x.hi - L.x.lo;
    gap = L.plot_width / std::max(unit, 1e-300);
  }
  b.slot_px = std::min(0.8 * gap, 0.5 * L.plot_width);
  return b;
}

// The shaded band of a series (Series::y_band): one closed path per run of
// consecutive drawn points with a finite half-width.
std::string band_path(const Figure& f, const Layout& L, const Series& s) {
  std::string d;
  std::vector<std::pair<double, double>> upper, lower;
  auto flush = [&]() {
    if (upper.size() >= 2) {
      d += (d.empty() ? "M" : " M") + px(upper[0].first) + "," + px(upper[0].second);
      for (size_t k = 1; k < upper.size(); ++k)
        d += " L" + px(upper[k].first) + "," + px(upper[k].second);
      for (size_t k = lower.size(); k-- > 0;)
        d += " L" + px(lower[k].first) + "," + px(lower[k].second);
      d += " Z";
    }
    upper.clear();
    lower.clear();
  };
  const double bottom = L.plot_top + L.plot_height;
  for (size_t k = 0; k < s.x.size(); ++k) {
    const double w = s.y_band.empty() ? NAN : s.y_band[k];
    if (!drawable(f, s.x[k], s.y[k]) || !std::isfinite(w)) {
      flush();
      continue;
    }
    const double cx = L.x.to_px(s.x[k]);
    upper.push_back({cx, L.y.to_px(s.y[k] + w)});
    lower.push_back({cx, (L.y.log && s.y[k] - w <= 0) ? bottom : L.y.to_px(s.y[k] - w)});
  }
  flush();
  return d;
}

void draw_series(const Figure& f, const Layout& L, size_t index, const std::string& colour,
                 const BarSlots& bars, int bar_index, std::string& o) {
  const Series& s = f.series[index];
  const std::string c = escape(colour);
  const double bottom = L.plot_top + L.plot_height;
  const double baseline =
      L.y.log ? bottom
              : L.y.to_px(std::clamp(0.0, std::min(L.y.lo, L.y.hi), std::max(L.y.lo, L.y.hi)));
  o += "<g class=\"series\"" + attr("data-label", escape(s.label)) + ">";
  std::string bars_svg, errors_svg, lines_svg, markers_svg;
  std::vector<std::string> segments(1);
  std::vector<size_t> segment_points(1, 0);
  std::vector<std::pair<double, double>> last_point(1);
  for (size_t k = 0; k < s.x.size(); ++k) {
    if (!drawable(f, s.x[k], s.y[k])) {
      if (segment_points.back() > 0) {
        segments.emplace_back();
        segment_points.push_back(0);
        last_point.emplace_back();
      }
      continue;
    }
    double cx = L.x.to_px(s.x[k]);
    const double cy = L.y.to_px(s.y[k]);
    if (s.style == SeriesStyle::kBars) {
      const double w = bars.slot_px / bars.count;
      const double left = cx - 0.5 * bars.slot_px + bar_index * w;
      cx = left + 0.5 * w;
      bars_svg += "<rect class=\"mark bar\"" + attr("x", px(left)) +
                  attr("y", px(std::min(cy, baseline))) + attr("width", px(w)) +
                  attr("height", px(std::fabs(baseline - cy))) + "/>";
    }
    const double err = s.y_error.empty() ? NAN : s.y_error[k];
    if (std::isfinite(err)) {
      const double hi = L.y.to_px(s.y[k] + err);
      const double lo = (L.y.log && s.y[k] - err <= 0) ? bottom : L.y.to_px(s.y[k] - err);
      const std::string x0 = px(cx - 3), x1 = px(cx + 3);
      errors_svg += "<path class=\"error-bar\"" +
                    attr("d", "M" + px(cx) + "," + px(lo) + " V" + px(hi) + " M" + x0 + "," +
                                  px(hi) + " H" + x1 + " M" + x0 + "," + px(lo) + " H" + x1) +
                    "/>";
    }
    if (has_line(s.style)) {
      segments.back() += (segment_points.back() ? " " : "") + px(cx) + "," + px(cy);
      ++segment_points.back();
      last_point.back() = {cx, cy};
    }
    if (has_markers(s.style)) markers_svg += marker(shape_of(s, index), cx, cy, colour, "mark");
  }
  for (size_t g = 0; g < segments.size(); ++g) {
    if (segment_points[g] == 0) continue;
    if (segment_points[g] == 1 && !has_markers(s.style)) {  // a lone point of a line: show it
      markers_svg +=
          marker(shape_of(s, index), last_point[g].first, last_point[g].second, colour, "mark");
      continue;
    }
    lines_svg += "<polyline class=\"mark line\"" + attr("points", segments[g]) + "/>";
  }
  if (const std::string band = band_path(f, L, s); !band.empty())
    o += "<path class=\"band\"" + attr("d", band) + attr("fill", c) +
         attr("fill-opacity", s.dashed ? "0.08" : "0.15") + attr("stroke", "none") + "/>";
  if (!bars_svg.empty())
    o += "<g" + attr("fill", c) + attr("fill-opacity", s.dashed ? "0.35" : "0.8") +
         attr("stroke", c) + stroke_dash(s) + ">" + bars_svg + "</g>";
  if (!errors_svg.empty())
    o += "<g" + attr("fill", "none") + attr("stroke", c) + attr("stroke-width", "1.2") + ">" +
         errors_svg + "</g>";
  if (!lines_svg.empty())
    o += "<g" + attr("fill", "none") + attr("stroke", c) + attr("stroke-width", "1.8") +
         attr("stroke-linejoin", "round") + stroke_dash(s) + ">" + lines_svg + "</g>";
  o += markers_svg + "</g>";
}

void draw_legend_sample(const Series& s, size_t index, const std::string& colour, double x,
                        double cy, std::string& o) {
  const std::string c = escape(colour);
  if (s.style == SeriesStyle::kBars) {
    o += "<rect" + attr("x", px(x + 5)) + attr("y", px(cy - 5)) + attr("width", "14") +
         attr("height", "10") + attr("fill", c) + attr("fill-opacity", s.dashed ? "0.35" : "0.8") +
         attr("stroke", c) + stroke_dash(s) + "/>";
    return;
  }
  if (has_line(s.style))
    o += "<line" + attr("x1", px(x)) + attr("y1", px(cy)) + attr("x2", px(x + kLegendSample)) +
         attr("y2", px(cy)) + attr("stroke", c) + attr("stroke-width", "1.8") + stroke_dash(s) +
         "/>";
  if (has_markers(s.style))
    o += marker(shape_of(s, index), x + 0.5 * kLegendSample, cy, colour, "");
}

void draw_axes(const Figure& f, const Layout& L, std::string& o) {
  const double bottom = L.plot_top + L.plot_height;
  const BelowPlot below = below_plot(f, 0);  // the legend is below what is drawn here
  // Tick marks, outward, and labels.
  o += "<g class=\"axes\" stroke=\"#222222\" stroke-width=\"1\">";
  o += "<rect" + attr("x", px(L.plot_left)) + attr("y", px(L.plot_top)) +
       attr("width", px(L.plot_width)) + attr("height", px(L.plot_height)) + " fill=\"none\"/>";
  std::string ticks;
  for (double t : L.x.ticks)
    ticks += "M" + px(L.x.to_px(t)) + "," + px(bottom) + " v" + px(kTickLength) + " ";
  for (double t : L.y.ticks)
    ticks += "M" + px(L.plot_left) + "," + px(L.y.to_px(t)) + " h" + px(-kTickLength) + " ";
  if (!ticks.empty()) {
    ticks.pop_back();
    o += "<path class=\"ticks\"" + attr("d", ticks) + "/>";
  }
  o += "</g>";
  o += "<g class=\"tick-labels\" fill=\"#222222\"" + attr("font-size", px(kTickFont)) + ">";
  const std::vector<std::string> xl = tick_labels(L.x), yl = tick_labels(L.y);
  for (size_t k = 0; k < xl.size(); ++k)
    o += "<text text-anchor=\"middle\"" + attr("x", px(L.x.to_px(L.x.ticks[k]))) +
         attr("y", px(bottom + below.tick_label)) + ">" + escape(xl[k]) + "</text>";
  for (size_t k = 0; k < yl.size(); ++k)
    o += "<text text-anchor=\"end\"" + attr("x", px(L.plot_left - kTickLength - 3)) +
         attr("y", px(L.y.to_px(L.y.ticks[k]) + 0.35 * kTickFont)) + ">" + escape(yl[k]) +
         "</text>";
  o += "</g>";
  const std::string xt = axis_title(f.x), yt = axis_title(f.y);
  if (!xt.empty())
    o += "<text class=\"axis-title x-title\" text-anchor=\"middle\"" +
         attr("x", px(L.plot_left + 0.5 * L.plot_width)) + attr("y", px(bottom + below.x_title)) +
         attr("font-size", px(kAxisFont)) + " fill=\"#111111\">" + escape(xt) + "</text>";
  if (!yt.empty())
    o += "<text class=\"axis-title y-title\" text-anchor=\"middle\"" +
         attr("transform", "translate(" + px(8 + kAxisFont) + "," +
                               px(L.plot_top + 0.5 * L.plot_height) + ") rotate(-90)") +
         attr("font-size", px(kAxisFont)) + " fill=\"#111111\">" + escape(yt) + "</text>";
}

void draw_grid(const Layout& L, std::string& o) {
  const double bottom = L.plot_top + L.plot_height, right = L.plot_left + L.plot_width;
  std::string d;
  for (double t : L.x.ticks)
    d += "M" + px(L.x.to_px(t)) + "," + px(L.plot_top) + " V" + px(bottom) + " ";
  for (double t : L.y.ticks)
    d += "M" + px(L.plot_left) + "," + px(L.y.to_px(t)) + " H" + px(right) + " ";
  if (!d.empty()) {
    d.pop_back();
    o += "<path class=\"grid\"" + attr("d", d) + " stroke=\"#e2e2e2\" stroke-width=\"1\"/>";
  }
  // y = 0 stands out when it lies inside a linear range: the reference for
  // errors and residuals.
  if (!L.y.log && L.y.lo < 0 && L.y.hi > 0)
    o += "<path class=\"zero-line\"" +
         attr("d", "M" + px(L.plot_left) + "," + px(L.y.to_px(0)) + " H" + px(right)) +
         " stroke=\"#9a9a9a\" stroke-width=\"1\"/>";
}

}  // namespace

std::string render_svg(const Figure& f) {
  const Layout L = layout(f);
  const std::string id = f.id;  // validated: safe in attributes and url(#...)
  const double bottom = L.plot_top + L.plot_height;
  std::string o;
  o.reserve(8192);
  o += "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\"" +
       attr("viewBox", "0 0 " + px(L.width) + " " + px(L.height)) + attr("width", px(L.width)) +
       attr("height", px(L.height)) + " role=\"img\"" + attr("aria-labelledby", id + "-title") +
       " font-family=\"sans-serif\">";
  o += "<title" + attr("id", id + "-title") + ">" + escape(f.title.empty() ? f.id : f.title) +
       "</title>";
  o += "<rect" + attr("width", px(L.width)) + attr("height", px(L.height)) + " fill=\"#ffffff\"/>";
  if (!f.title.empty())
    o += "<text class=\"title\" text-anchor=\"middle\"" + attr("x", px(0.5 * L.width)) +
         attr("y", "22") + attr("font-size", px(kTitleFont)) +
         " font-weight=\"bold\" fill=\"#111111\">" + escape(f.title) + "</text>";
  draw_grid(L, o);
  o += "<clipPath" + attr("id", id + "-plot-area") + "><rect" + attr("x", px(L.plot_left)) +
       attr("y", px(L.plot_top)) + attr("width", px(L.plot_width)) +
       attr("height", px(L.plot_height)) + "/></clipPath>";
  o += "<g class=\"data\"" + attr("clip-path", "url(#" + id + "-plot-area)") + ">";
  // Colours: explicit ones as given, the others from the palette in series order.
  std::vector<std::string> colours;
  int next_colour = 0;
  for (const Series& s : f.series)
    colours.push_back(!s.colour.empty() ? s.colour : kPalette[next_colour++ % kPaletteSize]);
  const BarSlots bars = bar_slots(f, L);
  // Bars first so that lines and markers of other series stay visible on top.
  int bar_index = 0;
  for (size_t i = 0; i < f.series.size(); ++i)
    if (f.series[i].style == SeriesStyle::kBars)
      draw_series(f, L, i, colours[i], bars, bar_index++, o);
  // Then markers alone, then anything with a line: a fitted line or a class
  // curve stays visible above a cloud of points.
  for (size_t i = 0; i < f.series.size(); ++i)
    if (f.series[i].style == SeriesStyle::kMarkers) draw_series(f, L, i, colours[i], bars, 0, o);
  for (size_t i = 0; i < f.series.size(); ++i)
    if (has_line(f.series[i].style)) draw_series(f, L, i, colours[i], bars, 0, o);
  o += "</g>";
  draw_axes(f, L, o);
  if (drawn_point_count(f) == 0)
    o += "<text class=\"no-data\" text-anchor=\"middle\"" +
         attr("x", px(L.plot_left + 0.5 * L.plot_width)) +
         attr("y", px(L.plot_top + 0.5 * L.plot_height)) + attr("font-size", px(kAxisFont)) +
         " fill=\"#555555\">no data</text>";
  int rows = 0;
  const std::vector<LegendItem> items = legend_items(f, L.width, &rows);
  const BelowPlot below = below_plot(f, rows);
  if (!items.empty()) {
    o += "<g class=\"legend\"" + attr("font-size", px(kLegendFont)) + " fill=\"#111111\">";
    for (const LegendItem& item : items) {
      const double cy = bottom + below.legend_top + item.y + 0.5 * kLegendRow;
      o += "<g class=\"legend-entry\">";
      draw_legend_sample(f.series[item.series], item.series, colours[item.series], item.x, cy, o);
      o += "<text" + attr("x", px(item.x + kLegendSample + 6)) +
           attr("y", px(cy + 0.35 * kLegendFont)) + ">" + escape(item.text);
      if (item.text != f.series[item.series].label)  // the whole label as a tooltip
        o += "<title>" + escape(f.series[item.series].label) + "</title>";
      o += "</text></g>";
    }
    o += "</g>";
  }
  const std::string note = notes_text(f);
  if (!note.empty())
    o += "<text class=\"note\"" + attr("x", "12") + attr("y", px(bottom + below.note)) +
         attr("font-size", px(kNoteFont)) + " fill=\"#555555\">" + escape(note) + "</text>";
  o += "</svg>";
  return o;
}

}  // namespace db::report::svg
