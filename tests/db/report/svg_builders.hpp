// Short builders for db::svg value types in tests: brace-initialising the
// aggregates positionally trips -Wmissing-field-initializers.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "db/report/svg_plot.hpp"

namespace svg_builders {

inline db::report::svg::Axis Ax(std::string label, std::string unit, bool log = false,
                                std::optional<double> min = std::nullopt,
                                std::optional<double> max = std::nullopt) {
  db::report::svg::Axis a;
  a.label = std::move(label);
  a.unit = std::move(unit);
  a.log = log;
  a.min = min;
  a.max = max;
  return a;
}

inline db::report::svg::Series Pts(
    std::string label, std::vector<double> x, std::vector<double> y,
    std::vector<double> y_error = {},
    db::report::svg::SeriesStyle style = db::report::svg::SeriesStyle::kMarkers,
    bool dashed = false) {
  db::report::svg::Series s;
  s.label = std::move(label);
  s.x = std::move(x);
  s.y = std::move(y);
  s.y_error = std::move(y_error);
  s.style = style;
  s.dashed = dashed;
  return s;
}

}  // namespace svg_builders
