#include "report_units.hpp"

#include <cmath>
#include <cstdio>
#include <map>

#include "report_document.hpp"

namespace db::report {
namespace {

// Places that give `scaled_max` four significant digits, 0..4.
int decimals_for(double scaled_max) {
  if (!(scaled_max > 0) || !std::isfinite(scaled_max)) return 2;
  const int magnitude = static_cast<int>(std::floor(std::log10(scaled_max)));
  return std::max(0, std::min(4, 3 - magnitude));
}

DisplayUnit scaled(double scale, const char* symbol, double max_abs, int extra_digits = 0) {
  const double m = std::isfinite(max_abs) ? max_abs * scale : 0.0;
  return {scale, std::min(4, decimals_for(m) + extra_digits), symbol};
}

// Replaces the last "(...)" of a header by "(symbol)", or appends it.
std::string with_unit(const std::string& header, const std::string& symbol, bool replace) {
  if (symbol.empty()) return header;
  const std::size_t open = header.rfind(" (");
  if (replace && open != std::string::npos && header.back() == ')')
    return header.substr(0, open) + " (" + symbol + ")";
  return header + " (" + symbol + ")";
}

}  // namespace

DisplayUnit display_unit(Quantity quantity, double max_abs) {
  const double m = std::isfinite(max_abs) ? std::fabs(max_abs) : 0.0;
  switch (quantity) {
    case Quantity::kLength:
      return m >= 1e-3 ? scaled(1e3, "mm", m) : scaled(1e6, "µm", m);
    case Quantity::kArea:
      return m >= 1e-6 ? scaled(1e6, "mm²", m) : scaled(1e12, "µm²", m);
    case Quantity::kDuration:
      return m >= 1 ? scaled(1, "s", m) : m >= 1e-3 ? scaled(1e3, "ms", m) : scaled(1e6, "µs", m);
    case Quantity::kMicroseconds:
      return scaled(1, "µs", m);
    case Quantity::kPixels:
      return scaled(1, "px", m);
    case Quantity::kPixelsSq:
      return scaled(1, "px²", m);
    case Quantity::kPercent:
      return scaled(1, "%", m);
    case Quantity::kFraction:
      return scaled(100, "%", m);
    case Quantity::kPlain:  // slopes near 1 need their fourth decimal
      return scaled(1, "", m, 1);
    case Quantity::kNone:
      break;
  }
  return scaled(1, "", m);
}

std::string fixed(double value, const DisplayUnit& unit) {
  if (std::isnan(value)) return "n/a";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", unit.decimals, value * unit.scale);
  std::string text = buffer;
  if (text[0] == '-' && text.find_first_not_of("-0.") == std::string::npos) text.erase(0, 1);
  return text;
}

std::string length_text(double metres) {
  const DisplayUnit u = display_unit(Quantity::kLength, metres);
  return fixed(metres, u) + " " + u.symbol;
}

html::Cell quantity_cell(double value, Quantity quantity, const std::string& css) {
  html::Cell c{num(value), css, ""};
  c.value = value;
  c.quantity = static_cast<int>(quantity);
  return c;
}

html::Table display_table(html::Table t) {
  const std::size_t columns = t.header.size();
  for (std::size_t col = 0; col < columns; ++col) {
    std::map<int, double> max_abs;  // per quantity in this column
    for (const auto& row : t.rows) {
      if (col >= row.size() || row[col].quantity == 0) continue;
      const double v = std::fabs(row[col].value);
      double& m = max_abs[row[col].quantity];
      if (std::isfinite(v) && v > m) m = v;
    }
    if (max_abs.empty()) continue;
    std::map<int, DisplayUnit> units;
    for (const auto& [q, m] : max_abs)
      units[q] = display_unit(static_cast<Quantity>(q), m);
    for (auto& row : t.rows) {
      if (col >= row.size() || row[col].quantity == 0) continue;
      row[col].text = fixed(row[col].value, units[row[col].quantity]);
    }
    if (units.size() == 1) {
      const auto& [q, unit] = *units.begin();
      const Quantity quantity = static_cast<Quantity>(q);
      const bool si_in_header = quantity == Quantity::kLength || quantity == Quantity::kArea ||
                                quantity == Quantity::kDuration;
      if (si_in_header || quantity == Quantity::kFraction)
        t.header[col] = with_unit(t.header[col], unit.symbol, si_in_header);
    }
  }
  return t;
}

}  // namespace db::report
