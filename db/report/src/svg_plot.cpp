// SVG figures for the reports (see svg_plot.hpp): layout, then one pass
// writing grid, axes, data marks, legend and notes as plain SVG elements with
// presentation attributes, so the SVG looks the same inside the page, saved
// alone, or printed.
#include "db/report/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "svg_detail.hpp"

namespace db::report::svg {
namespace {

using namespace detail;

constexpr double kPadding = 0.04;  // of the data span, on each unfixed side

bool id_is_valid(const std::string& id) {
  if (id.empty()) return false;
  for (char c : id) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_' || c == '.';
    if (!ok) return false;
  }
  return true;
}

std::string series_name(const Figure& f, size_t i) {
  return "figure '" + f.id + "' series " + std::to_string(i) + " ('" + f.series[i].label + "')";
}

void validate(const Figure& f) {
  if (!id_is_valid(f.id))
    throw std::invalid_argument("render_svg: figure id '" + f.id + "' (title '" + f.title +
                                "') must be non-empty and use only A-Z a-z 0-9 - _ .");
  if (f.width_px < 200 || f.height_px < 150)
    throw std::invalid_argument("render_svg: figure '" + f.id + "' size " +
                                std::to_string(f.width_px) + " x " + std::to_string(f.height_px) +
                                " px is below the minimum 200 x 150");
  for (size_t i = 0; i < f.series.size(); ++i) {
    const Series& s = f.series[i];
    if (s.x.size() != s.y.size())
      throw std::invalid_argument("render_svg: " + series_name(f, i) + " has " +
                                  std::to_string(s.x.size()) + " x values but " +
                                  std::to_string(s.y.size()) + " y values");
    if (!s.y_error.empty() && s.y_error.size() != s.y.size())
      throw std::invalid_argument("render_svg: " + series_name(f, i) + " has " +
                                  std::to_string(s.y_error.size()) + " y_error values for " +
                                  std::to_string(s.y.size()) + " points (expected 0 or " +
                                  std::to_string(s.y.size()) + ")");
    if (!s.y_band.empty() && s.y_band.size() != s.y.size())
      throw std::invalid_argument("render_svg: " + series_name(f, i) + " has " +
                                  std::to_string(s.y_band.size()) + " y_band values for " +
                                  std::to_string(s.y.size()) + " points (expected 0 or " +
                                  std::to_string(s.y.size()) + ")");
    for (size_t k = 0; k < s.y_band.size(); ++k)
      if (s.y_band[k] < 0)
        throw std::invalid_argument("render_svg: " + series_name(f, i) + " y_band[" +
                                    std::to_string(k) + "] = " + number(s.y_band[k]) +
                                    " is negative (expected a half-width >= 0)");
    for (size_t k = 0; k < s.y_error.size(); ++k)
      if (s.y_error[k] < 0)
        throw std::invalid_argument("render_svg: " + series_name(f, i) + " y_error[" +
                                    std::to_string(k) + "] = " + number(s.y_error[k]) +
                                    " is negative (expected a half-length >= 0)");
  }
  for (const auto* axis : {&f.x, &f.y}) {
    const char* name = axis == &f.x ? "x" : "y";
    if (axis->min && axis->max && !(*axis->min < *axis->max))
      throw std::invalid_argument("render_svg: figure '" + f.id + "' " + name + " axis min " +
                                  number(*axis->min) + " must be below max " + number(*axis->max));
    for (const auto& bound : {axis->min, axis->max})
      if (bound && (!std::isfinite(*bound) || (axis->log && *bound <= 0)))
        throw std::invalid_argument("render_svg: figure '" + f.id + "' " + name + " axis bound " +
                                    number(*bound) + " must be finite" +
                                    (axis->log ? " and > 0 on a log axis" : ""));
  }
}

bool has_bars(const Series& s) {
  return s.style == SeriesStyle::kBars;
}

// Axis coordinate (log10 on a log axis) of a value.
double axis_coord(const Axis& a, double v) {
  return a.log ? std::log10(v) : v;
}

struct Extent {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool empty() const { return lo > hi; }
};

// Range of the data in axis coordinates, before padding.
Extent data_extent(const Figure& f, bool is_x) {
  const Axis& axis = is_x ? f.x : f.y;
  Extent e;
  std::vector<double> bar_x;
  bool bars = false;
  for (const Series& s : f.series) {
    for (size_t k = 0; k < s.x.size(); ++k) {
      if (!drawable(f, s.x[k], s.y[k])) continue;
      if (is_x) {
        e.add(axis_coord(axis, s.x[k]));
        if (has_bars(s)) bar_x.push_back(axis_coord(axis, s.x[k]));
        continue;
      }
      e.add(axis_coord(axis, s.y[k]));
      for (const double err :
           {s.y_error.empty() ? NAN : s.y_error[k], s.y_band.empty() ? NAN : s.y_band[k]}) {
        if (!std::isfinite(err)) continue;
        e.add(axis_coord(axis, s.y[k] + err));
        if (!axis.log || s.y[k] - err > 0) e.add(axis_coord(axis, s.y[k] - err));
      }
      bars = bars || has_bars(s);
    }
  }
  if (!is_x && bars && !axis.log) e.add(0);  // bars start at 0
  if (is_x && !bar_x.empty()) {              // room for half a bar slot on each side
    std::sort(bar_x.begin(), bar_x.end());
    double gap = std::numeric_limits<double>::infinity();
    for (size_t k = 1; k < bar_x.size(); ++k)
      if (bar_x[k] > bar_x[k - 1]) gap = std::min(gap, bar_x[k] - bar_x[k - 1]);
    if (!std::isfinite(gap)) gap = 1;  // one x value: a slot one axis unit wide
    e.add(bar_x.front() - 0.5 * gap);
    e.add(bar_x.back() + 0.5 * gap);
  }
  return e;
}

// Range and ticks of one axis for a given pixel length.
Scale make_scale(const Figure& f, bool is_x, double length_px) {
  const Axis& axis = is_x ? f.x : f.y;
  const int target = is_x ? std::clamp(static_cast<int>(std::lround(length_px / 90)) + 1, 3, 10)
                          : std::clamp(static_cast<int>(std::lround(length_px / 55)) + 1, 3, 8);
  Extent e = data_extent(f, is_x);
  const double fixed_lo = axis.min ? axis_coord(axis, *axis.min) : NAN;
  const double fixed_hi = axis.max ? axis_coord(axis, *axis.max) : NAN;
  if (axis.min) e.lo = fixed_lo;
  if (axis.max) e.hi = fixed_hi;
  if (e.empty() || !std::isfinite(e.lo) || !std::isfinite(e.hi) || e.lo > e.hi) {
    // No data, or data entirely on the far side of a fixed bound: one unit
    // (one decade) next to the fixed bound, else [0, 1] ([1, 10]).
    if (axis.min && !axis.max) {
      e.lo = fixed_lo, e.hi = fixed_lo + 1;
    } else if (axis.max && !axis.min) {
      e.lo = fixed_hi - 1, e.hi = fixed_hi;
    } else if (!axis.min && !axis.max) {
      e.lo = 0, e.hi = 1;
    }
  }
  const bool no_data = data_extent(f, is_x).empty();
  // Bars rise from 0: no padding below (above) a 0 that bars put there.
  const bool bars_from_zero =
      !is_x && !axis.log &&
      std::any_of(f.series.begin(), f.series.end(), [](const Series& s) { return has_bars(s); });
  if (axis.log && e.hi - e.lo == 0 && !axis.min && !axis.max) {  // one value: a decade around it
    e.lo -= 0.5;
    e.hi += 0.5;
  }
  const Extent raw = e;
  const double span = e.hi - e.lo;
  if (!no_data && !axis.min && !(bars_from_zero && e.lo == 0)) e.lo -= kPadding * span;
  if (!no_data && !axis.max && !(bars_from_zero && e.hi == 0)) e.hi += kPadding * span;

  Scale s;
  s.log = axis.log;
  const auto value = [&](double c) { return axis.log ? std::pow(10.0, c) : c; };
  // Linear: the ticks enclosing the data, and the range covering both them
  // and the padded data (padding past a tick does not add a whole step).
  // Log: the padded data range (a whole extra decade would waste the plot),
  // extended to the enclosing ticks only if fewer than two fall inside.
  std::vector<double> ticks = axis.log ? nice_log_ticks(value(e.lo), value(e.hi), target)
                                       : nice_ticks(raw.lo, raw.hi, target);
  const auto inside = [&](double t, double lo, double hi) {
    return t >= lo * (1 - 1e-9) && t <= hi * (1 + 1e-9);
  };
  const bool extend = !axis.log || std::count_if(ticks.begin(), ticks.end(), [&](double t) {
                                     return inside(t, value(e.lo), value(e.hi));
                                   }) < 2;
  s.lo = axis.min ? *axis.min : extend ? std::min(ticks.front(), value(e.lo)) : value(e.lo);
  s.hi = axis.max ? *axis.max : extend ? std::max(ticks.back(), value(e.hi)) : value(e.hi);
  if (!(s.lo < s.hi)) {  // a single value: nice_ticks widened it, the ticks span it
    s.lo = ticks.front();
    s.hi = ticks.back();
  }
  // Ticks inside the range only (a fixed bound may cut the nice range).
  const double tol = 1e-9 * (axis.log ? 1 : std::max(std::fabs(s.lo), std::fabs(s.hi)));
  for (double t : ticks) {
    const bool inside = axis.log ? (t >= s.lo * (1 - 1e-9) && t <= s.hi * (1 + 1e-9))
                                 : (t >= s.lo - tol && t <= s.hi + tol);
    if (inside) s.ticks.push_back(t);
  }
  return s;
}

double tick_step(const Scale& s, size_t k) {
  if (s.log) return s.ticks[k];
  if (s.ticks.size() >= 2) return s.ticks[1] - s.ticks[0];
  return std::fabs(s.ticks[0]) > 0 ? std::fabs(s.ticks[0]) : 1;
}

struct Counts {
  size_t non_finite = 0, non_positive = 0, drawn = 0;
};

Counts count_points(const Figure& f) {
  Counts c;
  for (const Series& s : f.series)
    for (size_t k = 0; k < s.x.size(); ++k) {
      if (!std::isfinite(s.x[k]) || !std::isfinite(s.y[k]))
        ++c.non_finite;
      else if (!drawable(f, s.x[k], s.y[k]))
        ++c.non_positive;
      else
        ++c.drawn;
    }
  return c;
}

}  // namespace

namespace detail {

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        // XML 1.0 forbids most control characters even as references.
        out +=
            (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r') ? ' ' : c;
    }
  }
  return out;
}

// Pixel coordinates with two decimals (1/100 px is far below what shows),
// trailing zeros dropped to keep the file small.
std::string px(double v) {
  // Hundredths as an integer, written by hand: this runs several times per
  // data point and snprintf dominated the rendering time.
  const double hundredths = std::round(v * 100);
  if (!(std::fabs(hundredths) < 9e15)) return std::isnan(v) ? "0" : (v > 0 ? "1e9" : "-1e9");
  long long n = static_cast<long long>(hundredths);
  const bool negative = n < 0;
  if (negative) n = -n;
  char buf[32];
  char* end = buf + sizeof buf;
  char* p = end;
  const int fraction = static_cast<int>(n % 100);
  n /= 100;
  if (fraction != 0) {
    if (fraction % 10 != 0) *--p = static_cast<char>('0' + fraction % 10);
    *--p = static_cast<char>('0' + fraction / 10);
    *--p = '.';
  }
  do {
    *--p = static_cast<char>('0' + n % 10);
    n /= 10;
  } while (n > 0);
  if (negative && (fraction != 0 || p[0] != '0' || end - p > 1)) *--p = '-';
  return std::string(p, end);
}

double text_width(std::string_view text, double font_px) {
  size_t code_points = 0;
  for (char c : text)
    if ((static_cast<unsigned char>(c) & 0xC0) != 0x80) ++code_points;
  return static_cast<double>(code_points) * kCharEm * font_px;
}

std::string fit_text(const std::string& text, double width, double font_px) {
  if (text_width(text, font_px) <= width) return text;
  const double room = width - text_width("…", font_px);
  std::string out;
  for (size_t k = 0; k < text.size();) {
    size_t next = k + 1;
    while (next < text.size() && (static_cast<unsigned char>(text[next]) & 0xC0) == 0x80)
      ++next;
    if (text_width(out + text.substr(k, next - k), font_px) > room) break;
    out += text.substr(k, next - k);
    k = next;
  }
  return out + "…";
}

std::string axis_title(const Axis& axis) {
  if (axis.unit.empty()) return axis.label;
  if (axis.label.empty()) return "(" + axis.unit + ")";
  return axis.label + " (" + axis.unit + ")";
}

bool drawable(const Figure& f, double x, double y) {
  return std::isfinite(x) && std::isfinite(y) && !(f.x.log && x <= 0) && !(f.y.log && y <= 0);
}

std::vector<std::string> tick_labels(const Scale& s) {
  std::vector<std::string> out;
  for (size_t k = 0; k < s.ticks.size(); ++k)
    out.push_back(tick_label(s.ticks[k], tick_step(s, k)));
  return out;
}

size_t drawn_point_count(const Figure& f) {
  return count_points(f).drawn;
}

std::string notes_text(const Figure& f) {
  const Counts c = count_points(f);
  std::string note;
  if (c.non_finite > 0)
    note += std::to_string(c.non_finite) + (c.non_finite == 1 ? " point" : " points") +
            " not shown: not finite.";
  if (c.non_positive > 0)
    note += std::string(note.empty() ? "" : " ") + std::to_string(c.non_positive) +
            (c.non_positive == 1 ? " point" : " points") + " not shown: ≤ 0 on a log axis.";
  return note;
}

std::vector<LegendItem> legend_items(const Figure& f, double width, int* rows) {
  std::vector<LegendItem> items;
  const double left = 12, right = width - 12;
  double x = left;
  int row = 0;
  for (size_t i = 0; i < f.series.size(); ++i) {
    if (f.series[i].label.empty()) continue;
    const double frame = kLegendSample + 6 + 16;  // sample, gap, space to the next entry
    const std::string text = fit_text(f.series[i].label, right - left - frame, kLegendFont);
    const double w = frame + text_width(text, kLegendFont);
    if (x > left && x + w > right) {
      x = left;
      ++row;
    }
    items.push_back({i, x, row * kLegendRow, text});
    x += w;
  }
  *rows = items.empty() ? 0 : row + 1;
  return items;
}

BelowPlot below_plot(const Figure& f, int legend_rows) {
  BelowPlot b;
  b.tick_label = kTickLength + 3 + kTickFont;
  double y = b.tick_label;
  if (!axis_title(f.x).empty()) y = b.x_title = y + 8 + kAxisFont;
  b.legend_top = y + 10;
  if (legend_rows > 0) y = b.legend_top + legend_rows * kLegendRow;
  if (!notes_text(f).empty()) y = b.note = y + 6 + kNoteFont;
  b.total = y + 8;
  return b;
}

}  // namespace detail

double Scale::to_px(double v) const {
  const double t = log ? (std::log10(v) - std::log10(lo)) / (std::log10(hi) - std::log10(lo))
                       : (v - lo) / (hi - lo);
  return px_lo + t * (px_hi - px_lo);
}

Layout layout(const Figure& f) {
  validate(f);
  Layout L;
  L.width = f.width_px;
  int legend_rows = 0;
  legend_items(f, L.width, &legend_rows);
  const bool y_title = !axis_title(f.y).empty();
  const double top = f.title.empty() ? 12 : 34;
  const double bottom = below_plot(f, legend_rows).total;
  L.height = std::max<double>(f.height_px, top + bottom + 60);
  L.plot_top = top;
  L.plot_height = L.height - top - bottom;
  L.y = make_scale(f, false, L.plot_height);
  double label_w = 0;
  for (const std::string& s : tick_labels(L.y))
    label_w = std::max(label_w, text_width(s, kTickFont));
  L.plot_left = 8 + (y_title ? kAxisFont + 8 : 0) + label_w + 4 + kTickLength;
  // Right margin: room for half the last x tick label, centred on the edge.
  double right = 16;
  for (int pass = 0; pass < 2; ++pass) {
    L.plot_width = L.width - L.plot_left - right;
    L.x = make_scale(f, true, L.plot_width);
    const std::vector<std::string> labels = tick_labels(L.x);
    if (!labels.empty() && !L.x.ticks.empty() &&
        L.x.ticks.back() >= L.x.hi - 1e-9 * std::fabs(L.x.hi))
      right = std::max(16.0, 0.5 * text_width(labels.back(), kTickFont) + 4);
  }
  L.x.px_lo = L.plot_left;
  L.x.px_hi = L.plot_left + L.plot_width;
  L.y.px_lo = L.plot_top + L.plot_height;
  L.y.px_hi = L.plot_top;
  return L;
}

}  // namespace db::report::svg
