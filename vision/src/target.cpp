// Target layout: the paper's default sheet, TOML loading and validation
// (see vision/target.hpp).
#include "vision/target.hpp"

#include <cmath>
#include <limits>
#include <set>
#include <sstream>

#include "config/reader.hpp"
#include "vision/marker_family.hpp"

namespace vision {

namespace {

constexpr double kMmPerM = 1000.0;
constexpr std::int64_t kMaxInt = std::numeric_limits<int>::max();

std::string fmt_mm(double metres) {
  std::ostringstream s;
  s << metres * kMmPerM << " mm";
  return s.str();
}

// "FILE: KEY = VALUE: expected EXPECTED" for a value in memory.
[[noreturn]] void fail(const std::string& file, const std::string& key, const std::string& value,
                       const std::string& expected) {
  throw TargetError(config::error_message(file, key, value, expected));
}

// An [x_mm, y_mm] pair in metres.
Eigen::Vector2d pair_m(config::Table& t, const std::string& key) {
  const std::vector<double> v = t.numbers(key, 2, 2, "an array of two numbers [x_mm, y_mm]");
  return Eigen::Vector2d(v[0], v[1]) / kMmPerM;
}

// paper = "A4" | "A3" | "custom", and the sheet size in mm (required for a
// custom sheet, else optional and equal to the standard size).
void read_sheet(config::Table& root, Target* t) {
  const std::string paper = root.choice_or("paper", "A4", {"A4", "A3", "custom"});
  const bool custom = paper == "custom";
  const double standard_width_mm = paper == "A3" ? 297 : 210;
  const double standard_height_mm = paper == "A3" ? 420 : 297;
  const std::string expected = custom ? "a sheet size in mm > 0 (required for paper = \"custom\")"
                                      : "the size of " + paper + " (" +
                                            std::to_string(int(standard_width_mm)) + " x " +
                                            std::to_string(int(standard_height_mm)) + " mm)";
  const auto size_mm = [&](const char* key, double standard) {
    const config::NumberRule rule{
        expected, [&](double v) { return custom ? v > 0 : std::abs(v - standard) <= 1e-9; }};
    return custom ? root.number(key, rule) : root.number_or(key, standard, rule);
  };
  t->sheet_width_m = size_mm("sheet_width_mm", standard_width_mm) / kMmPerM;
  t->sheet_height_m = size_mm("sheet_height_mm", standard_height_mm) / kMmPerM;
}

TargetMarker read_marker(config::Table m) {
  TargetMarker marker;
  marker.id = static_cast<int>(m.integer("id", 0, kMaxInt, "an integer codebook id >= 0"));
  marker.side_m =
      m.number("side_mm", {"the marker side in mm > 0", [](double v) { return v > 0; }}) / kMmPerM;
  marker.centre_m = pair_m(m, "centre_mm");
  m.reject_unknown();
  return marker;
}

// [x0, x1] x [y0, y1] of a marker with its quiet zone, target frame.
Eigen::Vector4d footprint(const TargetMarker& m, int quiet_cells, int marker_cells) {
  const double half = m.side_m / 2 + quiet_cells * m.side_m / marker_cells;
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
  const config::Document file = config::Document::read<TargetError>(toml_path, "the target layout");
  config::Table root = file.root();
  Target t;
  t.name = root.string_or("name", "", "a name, free text");
  read_sheet(root, &t);
  t.sheet_origin_m = -pair_m(root, "origin_mm");
  t.pose_marker_id = static_cast<int>(
      root.integer("pose_marker", 0, kMaxInt, "the integer id of a listed marker"));
  t.quiet_cells =
      static_cast<int>(root.integer_or("quiet_cells", 1, 0, kMaxInt, "an integer >= 0"));
  t.family = root.choice_or("family", MarkerFamily::kDefaultName, MarkerFamily::names());
  for (config::Table& marker :
       root.tables("markers", "an array of tables [[markers]] with id, side_mm and centre_mm")) {
    t.markers.push_back(read_marker(marker));
  }
  root.reject_unknown();
  t.validate(toml_path);
  return t;
}

void Target::validate(const std::string& context) const {
  const std::string& f = context;
  const MarkerFamily* fam = nullptr;
  try {
    fam = &MarkerFamily::named(family);
  } catch (const MarkerFamilyError&) {
    fail(f, "family", "\"" + family + "\"", "one of " + MarkerFamily::names_text());
  }
  if (markers.empty()) {
    throw TargetError(
        config::error_message(f, "markers", std::nullopt, "at least one marker", "none given"));
  }
  if (!(sheet_width_m > 0)) fail(f, "sheet_width_mm", fmt_mm(sheet_width_m), "a size > 0 mm");
  if (!(sheet_height_m > 0)) fail(f, "sheet_height_mm", fmt_mm(sheet_height_m), "a size > 0 mm");
  if (quiet_cells < 0) fail(f, "quiet_cells", std::to_string(quiet_cells), "an integer >= 0");
  std::set<int> ids;
  for (size_t i = 0; i < markers.size(); ++i) {
    const TargetMarker& m = markers[i];
    const std::string prefix = "markers[" + std::to_string(i) + "].";
    if (!fam->has_id(m.id)) {
      fail(f, prefix + "id", std::to_string(m.id),
           "an id of family " + family + " (0 .. " + std::to_string(fam->size() - 1) + ")");
    }
    if (!ids.insert(m.id).second) {
      fail(f, prefix + "id", std::to_string(m.id), "an id not used by another marker");
    }
    if (!(m.side_m > 0) || !std::isfinite(m.side_m)) {
      fail(f, prefix + "side_mm", fmt_mm(m.side_m), "the marker side in mm > 0");
    }
    const Eigen::Vector4d box = footprint(m, quiet_cells, fam->marker_cells());
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
      const Eigen::Vector4d other = footprint(markers[j], quiet_cells, fam->marker_cells());
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
