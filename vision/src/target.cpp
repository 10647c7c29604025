// Target layout: the paper's default sheet, TOML loading and validation
// (see vision/target.hpp).
#include "vision/target.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <set>
#include <sstream>

#include "vision/codebook.hpp"

namespace vision {

namespace {

constexpr double kMmPerM = 1000.0;

std::string fmt_mm(double metres) {
  std::ostringstream s;
  s << metres * kMmPerM << " mm";
  return s.str();
}

// Error messages name the file, the key, the value and what was expected.
[[noreturn]] void fail(const std::string& file, const std::string& key, const std::string& value,
                       const std::string& expected) {
  throw TargetError(file + ": " + key + " = " + value + ": expected " + expected);
}

std::string describe(const toml::node* node) {
  if (node == nullptr) return "(missing)";
  std::ostringstream s;
  if (node->is_string()) {
    s << '"' << node->value_or(std::string()) << '"';
  } else if (node->is_array()) {
    s << *node->as_array();
  } else if (node->is_table()) {
    s << "(a table)";
  } else if (node->is_integer()) {
    s << node->value_or<int64_t>(0);
  } else if (node->is_floating_point()) {
    s << node->value_or(0.0);
  } else if (node->is_boolean()) {
    s << (node->value_or(false) ? "true" : "false");
  } else {
    s << "(a date/time)";
  }
  return s.str();
}

double number(const std::string& file, const std::string& key, const toml::node* node,
              const std::string& expected) {
  if (node == nullptr || !(node->is_integer() || node->is_floating_point())) {
    fail(file, key, describe(node), expected);
  }
  const double value = node->value_or(0.0);
  if (!std::isfinite(value)) fail(file, key, describe(node), expected);
  return value;
}

int integer(const std::string& file, const std::string& key, const toml::node* node,
            const std::string& expected) {
  if (node == nullptr || !node->is_integer()) fail(file, key, describe(node), expected);
  const int64_t value = node->value_or<int64_t>(0);
  if (value < -1000000 || value > 1000000) fail(file, key, describe(node), expected);
  return static_cast<int>(value);
}

Eigen::Vector2d pair_mm(const std::string& file, const std::string& key, const toml::node* node) {
  const std::string expected = "an array of two numbers [x_mm, y_mm]";
  const toml::array* array = node != nullptr ? node->as_array() : nullptr;
  if (array == nullptr || array->size() != 2) fail(file, key, describe(node), expected);
  Eigen::Vector2d v;
  for (size_t i = 0; i < 2; ++i) {
    const toml::node* e = array->get(i);
    if (!(e->is_integer() || e->is_floating_point()) || !std::isfinite(e->value_or(0.0))) {
      fail(file, key, describe(node), expected);
    }
    v[static_cast<Eigen::Index>(i)] = e->value_or(0.0) / kMmPerM;
  }
  return v;
}

// [x0, x1] x [y0, y1] of a marker with its quiet zone, target frame.
Eigen::Vector4d footprint(const TargetMarker& m, int quiet_cells) {
  const double half = m.side_m / 2 + quiet_cells * m.side_m / kMarkerCells;
  return {m.centre_m.x() - half, m.centre_m.x() + half, m.centre_m.y() - half,
          m.centre_m.y() + half};
}

}  // namespace

Target Target::paper_default() {
  Target t;
  t.name = "paper";
  t.sheet_width_m = 0.210;
  t.sheet_height_m = 0.297;
  t.sheet_origin_m = {-0.105, -0.1485};
  t.quiet_cells = 1;
  t.pose_marker_id = 0;
  t.markers = {{0, 0.050, {0.0, 0.0}},
               {1, 0.050, {-0.060, -0.090}},
               {2, 0.050, {0.060, -0.090}},
               {3, 0.050, {0.0, 0.090}}};
  return t;
}

Target Target::load(const std::string& toml_path) {
  toml::table root;
  try {
    root = toml::parse_file(toml_path);
  } catch (const toml::parse_error& e) {
    std::ostringstream s;
    s << toml_path << ": not a readable TOML layout file (" << e.description();
    if (e.source().begin.line > 0) s << " at line " << e.source().begin.line;
    s << ")";
    throw TargetError(s.str());
  }
  const std::string& f = toml_path;
  Target t;
  t.name = root["name"].value_or(std::string());

  const std::string paper = root["paper"].value_or(std::string("A4"));
  double width_mm = 0;
  double height_mm = 0;
  if (paper == "A4") {
    width_mm = 210;
    height_mm = 297;
  } else if (paper == "A3") {
    width_mm = 297;
    height_mm = 420;
  } else if (paper != "custom") {
    fail(f, "paper", describe(root.get("paper")), "\"A4\", \"A3\" or \"custom\"");
  }
  const char* width_key = "sheet_width_mm";
  const char* height_key = "sheet_height_mm";
  if (paper == "custom" || root.contains(width_key) || root.contains(height_key)) {
    const std::string expected =
        paper == "custom" ? "a sheet size in mm > 0 (required for paper = \"custom\")"
                          : "the size of " + paper + " (" + std::to_string(int(width_mm)) + " x " +
                                std::to_string(int(height_mm)) + " mm)";
    const double w = number(f, width_key, root.get(width_key), expected);
    const double h = number(f, height_key, root.get(height_key), expected);
    if (paper != "custom" && (std::abs(w - width_mm) > 1e-9 || std::abs(h - height_mm) > 1e-9)) {
      fail(f, std::abs(w - width_mm) > 1e-9 ? width_key : height_key,
           describe(root.get(std::abs(w - width_mm) > 1e-9 ? width_key : height_key)), expected);
    }
    if (w <= 0) fail(f, width_key, describe(root.get(width_key)), expected);
    if (h <= 0) fail(f, height_key, describe(root.get(height_key)), expected);
    width_mm = w;
    height_mm = h;
  }
  t.sheet_width_m = width_mm / kMmPerM;
  t.sheet_height_m = height_mm / kMmPerM;
  t.sheet_origin_m = -pair_mm(f, "origin_mm", root.get("origin_mm"));
  t.pose_marker_id =
      integer(f, "pose_marker", root.get("pose_marker"), "the integer id of a listed marker");
  t.quiet_cells = root.contains("quiet_cells")
                      ? integer(f, "quiet_cells", root.get("quiet_cells"), "an integer >= 0")
                      : 1;

  const toml::array* markers = root["markers"].as_array();
  if (markers == nullptr || markers->empty()) {
    fail(f, "markers", describe(root.get("markers")),
         "an array of tables [[markers]] with id, side_mm and centre_mm");
  }
  for (size_t i = 0; i < markers->size(); ++i) {
    const std::string prefix = "markers[" + std::to_string(i) + "].";
    const toml::table* m = markers->get(i)->as_table();
    if (m == nullptr) fail(f, "markers[" + std::to_string(i) + "]", "(not a table)", "a table");
    TargetMarker marker;
    marker.id = integer(f, prefix + "id", m->get("id"), "an integer codebook id >= 0");
    marker.side_m =
        number(f, prefix + "side_mm", m->get("side_mm"), "the marker side in mm > 0") / kMmPerM;
    marker.centre_m = pair_mm(f, prefix + "centre_mm", m->get("centre_mm"));
    t.markers.push_back(marker);
  }
  t.validate(toml_path);
  return t;
}

void Target::validate(const std::string& context) const {
  const std::string& f = context;
  if (markers.empty()) fail(f, "markers", "(none)", "at least one marker");
  if (!(sheet_width_m > 0) || !(sheet_height_m > 0)) {
    fail(f, "sheet size", fmt_mm(sheet_width_m) + " x " + fmt_mm(sheet_height_m), "> 0");
  }
  if (quiet_cells < 0) fail(f, "quiet_cells", std::to_string(quiet_cells), "an integer >= 0");
  std::set<int> ids;
  for (size_t i = 0; i < markers.size(); ++i) {
    const TargetMarker& m = markers[i];
    const std::string prefix = "markers[" + std::to_string(i) + "].";
    if (m.id < 0) fail(f, prefix + "id", std::to_string(m.id), "a codebook id >= 0");
    if (!ids.insert(m.id).second) {
      fail(f, prefix + "id", std::to_string(m.id), "an id not used by another marker");
    }
    if (!(m.side_m > 0) || !std::isfinite(m.side_m)) {
      fail(f, prefix + "side_mm", fmt_mm(m.side_m), "the marker side in mm > 0");
    }
    const Eigen::Vector4d box = footprint(m, quiet_cells);
    const double eps = 1e-9;
    if (box[0] < sheet_origin_m.x() - eps || box[1] > sheet_origin_m.x() + sheet_width_m + eps ||
        box[2] < sheet_origin_m.y() - eps || box[3] > sheet_origin_m.y() + sheet_height_m + eps) {
      std::ostringstream v;
      v << "[" << m.centre_m.x() * kMmPerM << ", " << m.centre_m.y() * kMmPerM << "]";
      fail(f, prefix + "centre_mm", v.str(),
           "the marker and its quiet zone inside the sheet (" + fmt_mm(sheet_width_m) + " x " +
               fmt_mm(sheet_height_m) + ", top-left corner at [" +
               std::to_string(sheet_origin_m.x() * kMmPerM) + ", " +
               std::to_string(sheet_origin_m.y() * kMmPerM) + "] mm in the target frame)");
    }
    for (size_t j = 0; j < i; ++j) {
      const Eigen::Vector4d other = footprint(markers[j], quiet_cells);
      const bool overlap = box[0] < other[1] - eps && other[0] < box[1] - eps &&
                           box[2] < other[3] - eps && other[2] < box[3] - eps;
      if (overlap) {
        std::ostringstream v;
        v << "[" << m.centre_m.x() * kMmPerM << ", " << m.centre_m.y() * kMmPerM << "]";
        fail(f, prefix + "centre_mm", v.str(),
             "a marker whose quiet zone does not overlap that of marker id " +
                 std::to_string(markers[j].id));
      }
    }
  }
  if (ids.count(pose_marker_id) == 0) {
    fail(f, "pose_marker", std::to_string(pose_marker_id), "the id of one of the markers");
  }
}

bool Target::has_marker(int id) const {
  for (const TargetMarker& m : markers) {
    if (m.id == id) return true;
  }
  return false;
}

const TargetMarker& Target::marker(int id) const {
  for (const TargetMarker& m : markers) {
    if (m.id == id) return m;
  }
  throw TargetError("target " + name + ": no marker with id " + std::to_string(id));
}

std::array<Eigen::Vector3d, 4> Target::corners_m(const TargetMarker& m) const {
  const double h = m.side_m / 2;
  const double x = m.centre_m.x();
  const double y = m.centre_m.y();
  return {Eigen::Vector3d(x - h, y - h, 0), Eigen::Vector3d(x + h, y - h, 0),
          Eigen::Vector3d(x + h, y + h, 0), Eigen::Vector3d(x - h, y + h, 0)};
}

}  // namespace vision
