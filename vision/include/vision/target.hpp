// vision::Target: the physical layout of a printed target sheet.
//
// Target frame (metres in this API, millimetres in the layout file): origin as
// set by the layout (the paper's sheet puts it at the centre of the pose
// marker), x to the right on the printed sheet, y down the sheet, z into the
// sheet (right-handed). A camera looking straight at the sheet, upright, has
// R_cam_target = I; the sheet is the plane z = 0.
//
// A marker (see vision/codebook.hpp) is an axis-aligned square of side s whose
// outer black border has the corners, in this order (as printed, x right, y down):
//   A = centre + (-s/2, -s/2, 0)  top-left
//   B = centre + (+s/2, -s/2, 0)  top-right
//   C = centre + (+s/2, +s/2, 0)  bottom-right
//   D = centre + (-s/2, +s/2, 0)  bottom-left
// The pose solvers take the pose marker's A, B, C, D as their first four points.
// Each marker is surrounded by a white quiet zone of quiet_cells cells
// (cell = s / marker_cells of the target's family, s / 6 for rig4x4) that no other marker and no
// sheet edge may enter.
//
// Layout file (TOML; lengths in mm), e.g. config/targets/paper.toml:
//   name = "paper"                 # optional, free text
//   paper = "A4"                   # "A4" (210 x 297), "A3" (297 x 420) or "custom"
//   sheet_width_mm = 210           # required only for paper = "custom"
//   sheet_height_mm = 297          #   (also allowed, must then match A4/A3)
//   origin_mm = [105.0, 148.5]     # target-frame origin, from the sheet's top-left corner
//   pose_marker = 0                # id of the marker that gives the pose
//   quiet_cells = 1                # optional, default 1
//   family = "rig4x4"              # optional, default rig4x4; one of
//                                  #   vision::MarkerFamily::names()
//   [[markers]]
//   id = 0                         # id in the family, >= 0, unique
//   side_mm = 50.0                 # > 0
//   centre_mm = [0.0, 0.0]         # in the target frame
// A key not listed is refused (a typo never falls back to a default). A bad
// file throws TargetError "FILE: KEY = VALUE: [PROBLEM; ]expected WHAT"
// (config/reader.hpp), e.g. "paper.toml: markers[1].side_mm = -5: expected
// the marker side in mm > 0".
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "config/error.hpp"

namespace vision {

// A layout that cannot be read or is inconsistent (missing or unknown key,
// wrong type, duplicate id, markers overlapping or off the sheet), or a marker
// id the layout does not hold. The message names the file, the key, the value
// and what was expected. A config::ConfigError: bad input.
class TargetError : public config::ConfigError {
 public:
  using config::ConfigError::ConfigError;
};

struct TargetMarker {
  int id = 0;                                          // codebook id
  double side_m = 0;                                   // outer side of the black border, metres
  Eigen::Vector2d centre_m = Eigen::Vector2d::Zero();  // centre in the target frame (z = 0), metres
};

struct Target {
  std::string name;
  std::vector<TargetMarker> markers;
  int pose_marker_id = 0;  // the marker whose corners give the pose
  // The sheet: a rectangle of sheet_width_m x sheet_height_m whose top-left
  // corner is at sheet_origin_m in the target frame (so the sheet spans
  // [x0, x0 + width] x [y0, y0 + height]).
  double sheet_width_m = 0.210;
  double sheet_height_m = 0.297;
  Eigen::Vector2d sheet_origin_m = Eigen::Vector2d(-0.105, -0.1485);
  // White quiet zone around each marker, in cells (cell = side / 6). The
  // detector needs at least one cell of white outside the border.
  int quiet_cells = 1;
  // The marker family the sheet is printed in (vision/marker_family.hpp):
  // one of MarkerFamily::names(); every marker id must be one of its ids.
  std::string family = "rig4x4";

  // The paper's sheet (what config/targets/paper.toml holds): A4 portrait,
  // four 5 cm markers, ids 0-3. Marker 0 is the pose marker, centred at the
  // target-frame origin at the centre of the sheet; markers 1, 2, 3 (used for
  // the generalization error) are centred at (-60, -90), (60, -90) and
  // (0, 90) mm.
  static Target paper_default();

  // Reads a layout file (format above; a regular file of at most 1 MiB) and
  // validates it. Throws TargetError.
  static Target load(const std::string& toml_path);

  // Checks the invariants: a known family, at least one marker, unique ids of
  // that family, sides > 0,
  // pose_marker_id among the markers, quiet_cells >= 0, markers with their
  // quiet zones inside the sheet and not overlapping. Throws TargetError
  // (the message starts with `context`, e.g. the file name).
  void validate(const std::string& context = "target") const;

  bool has_marker(int id) const;
  // Precondition: has_marker(id); TargetError otherwise.
  const TargetMarker& marker(int id) const;
  const TargetMarker& pose_marker() const { return marker(pose_marker_id); }

  // Outer corners A, B, C, D of a marker's black border in the target frame
  // (z = 0), metres, in the order documented above.
  std::array<Eigen::Vector3d, 4> corners_m(const TargetMarker& marker) const;
  std::array<Eigen::Vector3d, 4> corners_m(int id) const { return corners_m(marker(id)); }
};

}  // namespace vision
