// The YAML of camera calibration files, read without OpenCV's YAML parser
// (private to vision; vision::Camera::load uses it).
//
// OpenCV 4.6's YAML reader aborts the process (std::terminate: an exception
// rethrown through a frame that cannot pass it) on some malformed block
// mappings, e.g. a line "   :d td" inside an !!opencv-matrix (found by
// libFuzzer). A calibration file is a small, regular subset of YAML, and this
// reader accepts that subset only, refusing anything else with the file, the
// line and what was expected:
//
//   %YAML:1.0                          optional directive (OpenCV writes it),
//   ---                                optional document start
//   # comment                          whole-line and trailing comments
//   image_width: 736                   KEY: SCALAR (number, plain or quoted text)
//   camera_matrix: !!opencv-matrix     KEY: [!!opencv-matrix] and an indented
//      rows: 3                         block of KEY: VALUE (OpenCV matrix, or
//      dt: d                           ROS's {rows, cols, data})
//      data: [ 706.1, 0., 388.0,       KEY: [flow, sequence, of, scalars],
//          0., 731.1, 269.6 ]          which may continue over lines
//
// Keys are [A-Za-z_][A-Za-z0-9_.-]*, indentation is spaces, blocks nest at
// most kMaxBlockDepth levels. Not accepted: tabs in indentation, block
// sequences ("- item"), flow mappings ("{...}"), nested flow sequences,
// anchors, aliases, other tags, multi-line and block scalars, several
// documents, a key given twice.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace vision::calibration {

// A node of a calibration file, YAML or XML (the XML one is converted from
// OpenCV's FileNode). A scalar that reads as a number whole has `number`
// (and `integer` when it is written as one, e.g. "3", not "3." or "3e0").
struct Node {
  enum class Kind { kScalar, kSequence, kMap };
  Kind kind = Kind::kScalar;
  std::string text;  // a scalar as written, quotes removed
  std::optional<double> number;
  bool integer = false;
  std::string tag;                                    // "opencv-matrix" or ""
  std::vector<Node> items;                            // kSequence
  std::vector<std::pair<std::string, Node>> entries;  // kMap, in file order
  int line = 0;                                       // 1-based; 0 when unknown (XML)

  // The entry `key` of a map, or null (also for a node that is no map).
  const Node* find(const std::string& key) const;
};

// Blocks (the top-level map counts as one) nest at most this deep; a
// calibration needs 2.
constexpr int kMaxBlockDepth = 8;

// Parses `text`, the whole file `path`, as the subset above; returns its
// top-level map. Throws vision::CalibrationError
// "calibration file 'PATH': line N: PROBLEM; expected WHAT" for anything else.
Node parse_yaml(const std::string& path, const std::string& text);

// The number a scalar's text reads as whole, if any: decimal integers and
// floating-point numbers ("706.1", "0.", "-2.2e-01", "+1"); not ".inf",
// ".nan", hexadecimal or text around a number.
std::optional<double> parse_number(const std::string& text, bool* integer);

}  // namespace vision::calibration
