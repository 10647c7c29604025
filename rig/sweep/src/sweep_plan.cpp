// Sweep plans: grid, CSV, the paper's preset, JSON (see sweep_plan.hpp).
#include "rig/sweep/sweep_plan.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "config/reader.hpp"

namespace rig::sweep {
namespace {

// Two values closer than this (mm) are the same grid value: a step that
// divides the range up to rounding must not add a second, 1e-13 mm shorter
// last step. A nanometre is a thousandth of the finest encoder count in use.
constexpr double kSameValueMm = 1e-6;

// The values of one grid axis: min, min + step, ..., then max exactly.
std::vector<double> axis_values(double min, double max, double step) {
  const double whole_steps = std::floor((max - min) / step);
  std::vector<double> values;
  values.reserve(static_cast<std::size_t>(whole_steps) + 2);
  for (double i = 0; i <= whole_steps; ++i)
    values.push_back(min + i * step);
  if (max - values.back() > kSameValueMm) {
    values.push_back(max);
  } else {
    values.back() = max;  // hit the end exactly, not up to rounding
  }
  return values;
}

// Axis values of a grid, checked; `axis` is "x" or "y".
std::vector<double> checked_axis(const std::string& axis, double min, double max, double step) {
  auto fail = [&](const std::string& key, double value, const std::string& expected) {
    throw PlanError("grid: " + axis + "_" + key + "_mm = " + config::format_number(value) +
                    ": expected " + expected);
  };
  if (!std::isfinite(min)) fail("min", min, "a finite number");
  if (!std::isfinite(max)) fail("max", max, "a finite number");
  if (!std::isfinite(step) || step <= 0) fail("step", step, "a finite number > 0");
  if (max < min) fail("max", max, ">= " + axis + "_min_mm (" + config::format_number(min) + ")");
  // Checked before the values are made, so a step of 1e-9 mm fails at once.
  if ((max - min) / step + 2 > static_cast<double>(SweepPlan::kMaxPositions)) {
    fail("step", step,
         "a step giving at most " + std::to_string(SweepPlan::kMaxPositions) + " positions over " +
             config::format_number(min) + ".." + config::format_number(max) + " mm");
  }
  return axis_values(min, max, step);
}

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos) return "";
  const auto last = s.find_last_not_of(" \t\r");
  return s.substr(first, last - first + 1);
}

// A whole field as a finite number, or false.
bool parse_number(const std::string& text, double* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return *end == '\0' && std::isfinite(*value);
}

}  // namespace

SweepPlan SweepPlan::grid(const Grid& g) {
  const std::vector<double> xs = checked_axis("x", g.x_min_mm, g.x_max_mm, g.x_step_mm);
  const std::vector<double> ys = checked_axis("y", g.y_min_mm, g.y_max_mm, g.y_step_mm);
  if (xs.size() * ys.size() > kMaxPositions) {
    throw PlanError("grid: " + std::to_string(xs.size()) + " x " + std::to_string(ys.size()) +
                    " positions: expected at most " + std::to_string(kMaxPositions) +
                    " (larger steps)");
  }
  std::vector<PlanPosition> positions;
  positions.reserve(xs.size() * ys.size());
  for (std::size_t row = 0; row < ys.size(); ++row) {
    const bool reversed = g.serpentine && row % 2 == 1;
    for (std::size_t i = 0; i < xs.size(); ++i) {
      positions.push_back({xs[reversed ? xs.size() - 1 - i : i], ys[row]});
    }
  }
  const std::string description =
      "grid x " + config::format_number(g.x_min_mm) + ".." + config::format_number(g.x_max_mm) +
      " step " + config::format_number(g.x_step_mm) + " mm, y " +
      config::format_number(g.y_min_mm) + ".." + config::format_number(g.y_max_mm) + " step " +
      config::format_number(g.y_step_mm) + " mm, " + (g.serpentine ? "serpentine" : "row by row") +
      " (" + std::to_string(positions.size()) + " positions)";
  return SweepPlan(std::move(positions), description);
}

SweepPlan SweepPlan::from_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw PlanError(path + ": cannot open the plan file (expected a readable CSV file)");
  std::vector<PlanPosition> positions;
  bool header_seen = false;
  int line_number = 0;
  for (std::string raw; std::getline(in, raw);) {
    ++line_number;
    // Spreadsheets export "CSV UTF-8" with a byte order mark; it is not part of the header.
    if (line_number == 1 && raw.rfind("\xEF\xBB\xBF", 0) == 0) raw.erase(0, 3);
    const std::string where = path + ":" + std::to_string(line_number) + ": ";
    const std::string line = trim(raw.substr(0, raw.find('#')));
    if (line.empty()) continue;
    const auto comma = line.find(',');
    const std::string first = trim(line.substr(0, comma));
    const std::string rest = comma == std::string::npos ? "" : line.substr(comma + 1);
    if (!header_seen) {
      if (comma == std::string::npos || first != "x_mm" || trim(rest) != "y_mm") {
        throw PlanError(where + "\"" + line + "\": expected the header \"x_mm,y_mm\"");
      }
      header_seen = true;
      continue;
    }
    if (comma == std::string::npos || rest.find(',') != std::string::npos) {
      throw PlanError(where + "\"" + line + "\": expected two fields \"X,Y\" (mm)");
    }
    PlanPosition p;
    if (!parse_number(first, &p.x_mm)) {
      throw PlanError(where + "x_mm = \"" + first + "\": expected a finite number (mm)");
    }
    if (!parse_number(trim(rest), &p.y_mm)) {
      throw PlanError(where + "y_mm = \"" + trim(rest) + "\": expected a finite number (mm)");
    }
    if (positions.size() == kMaxPositions) {
      throw PlanError(where + "expected at most " + std::to_string(kMaxPositions) + " positions");
    }
    positions.push_back(p);
  }
  if (in.bad()) throw PlanError(path + ": read error");
  if (!header_seen) throw PlanError(path + ": empty plan: expected the header \"x_mm,y_mm\"");
  if (positions.empty()) {
    throw PlanError(path + ": no positions after the header: expected at least one \"X,Y\" line");
  }
  const std::string description =
      "csv " + path + " (" + std::to_string(positions.size()) + " positions)";
  return SweepPlan(std::move(positions), description);
}

SweepPlan SweepPlan::paper(double x_min_mm, double x_max_mm, double y_min_mm, double y_max_mm) {
  auto check = [](const std::string& axis, double min, double max) {
    if (!std::isfinite(min) || !std::isfinite(max) || !(min < max)) {
      throw PlanError("paper plan: " + axis + " range " + config::format_number(min) + ".." +
                      config::format_number(max) + " mm: expected finite numbers with min < max");
    }
  };
  check("x", x_min_mm, x_max_mm);
  check("y", y_min_mm, y_max_mm);
  std::vector<PlanPosition> positions;
  positions.reserve(kPaperRows * kPaperColumns);
  // Evenly spaced by index (not by accumulating a step), so both ends are exact.
  auto at = [](double min, double max, int i, int n) {
    return i == n - 1 ? max : min + (max - min) * i / (n - 1);
  };
  for (int row = 0; row < kPaperRows; ++row) {
    const double y = at(y_min_mm, y_max_mm, row, kPaperRows);
    for (int i = 0; i < kPaperColumns; ++i) {
      const int column = row % 2 == 1 ? kPaperColumns - 1 - i : i;
      positions.push_back({at(x_min_mm, x_max_mm, column, kPaperColumns), y});
    }
  }
  const std::string description =
      "paper (Maidi et al. 2010): " + std::to_string(kPaperRows) + " rows x " +
      std::to_string(kPaperColumns) + " columns over x " + config::format_number(x_min_mm) + ".." +
      config::format_number(x_max_mm) + " mm, y " + config::format_number(y_min_mm) + ".." +
      config::format_number(y_max_mm) + " mm, serpentine (" + std::to_string(positions.size()) +
      " positions)";
  return SweepPlan(std::move(positions), description);
}

nlohmann::json SweepPlan::to_json() const {
  nlohmann::json positions = nlohmann::json::array();
  for (const PlanPosition& p : positions_)
    positions.push_back({p.x_mm, p.y_mm});
  return {{"description", description_}, {"positions", std::move(positions)}};
}

SweepPlan SweepPlan::from_json(const nlohmann::json& json) {
  auto fail = [](const std::string& what) { throw PlanError("plan JSON: " + what); };
  if (!json.is_object()) {
    fail(std::string("a ") + json.type_name() +
         ": expected an object {\"description\": ..., \"positions\": [[x, y], ...]}");
  }
  for (const auto& item : json.items()) {
    if (item.key() != "description" && item.key() != "positions") {
      fail("unknown key \"" + item.key() + "\": expected only description and positions");
    }
  }
  const auto description = json.find("description");
  if (description == json.end() || !description->is_string()) {
    fail("description: expected a string");
  }
  const auto list = json.find("positions");
  if (list == json.end() || !list->is_array()) fail("positions: expected an array of [x, y]");
  if (list->empty()) fail("positions = []: expected at least one position");
  if (list->size() > kMaxPositions) {
    fail("positions: " + std::to_string(list->size()) + " entries: expected at most " +
         std::to_string(kMaxPositions));
  }
  std::vector<PlanPosition> positions;
  positions.reserve(list->size());
  for (std::size_t i = 0; i < list->size(); ++i) {
    const nlohmann::json& p = (*list)[i];
    const bool pair = p.is_array() && p.size() == 2 && p[0].is_number() && p[1].is_number();
    if (!pair || !std::isfinite(p[0].get<double>()) || !std::isfinite(p[1].get<double>())) {
      fail("positions[" + std::to_string(i) + "] = " + p.dump() +
           ": expected [x_mm, y_mm], two finite numbers");
    }
    positions.push_back({p[0].get<double>(), p[1].get<double>()});
  }
  return SweepPlan(std::move(positions), description->get<std::string>());
}

}  // namespace rig::sweep
