// vision::MarkerFamily: the bit patterns of a family of square fiducials.
//
// A marker of a family is a square grid of marker_cells() x marker_cells()
// equal cells (cell = side / marker_cells()): a black border of
// border_cells() cells around a code grid of code_cells() x code_cells()
// cells. For an id, cell_is_white() gives every cell as printed, seen from
// the front, row 0 on top, column 0 on the left. The side of a marker is the
// outer side of its black border for every family (rig's, ArUco's and
// AprilTag's own convention).
//
// Families (name: code cells, border, ids):
//   rig4x4                     4x4, 1, 35   rig's codebook (vision/codebook.hpp,
//                                           Maidi et al. 2010, DOI 10.1007/s00138-008-0170-y)
//   aruco:DICT_4X4_50          4x4, 1, 50   OpenCV ArUco dictionaries
//   aruco:DICT_6X6_250         6x6, 1, 250    (cv::aruco::getPredefinedDictionary,
//   aruco:DICT_APRILTAG_36h11  6x6, 1, 587    Garrido-Jurado et al. 2014,
//                                             DOI 10.1016/j.patcog.2014.01.005)
//   apriltag:tag36h11          6x6, 1, 587  AprilTag 3 families (libapriltag;
//   apriltag:tag16h5           4x4, 1, 30     Krogius et al. 2019,
//                                             DOI 10.1109/IROS40897.2019.8967787)
// ArUco cells come from Dictionary::getBitsFromByteList (1 = white, row-major);
// AprilTag cells from the family's codes: bit i of nbits (counted from the
// most significant) is the cell at column bit_x[i], row bit_y[i] of the grid
// whose origin is the outer corner of the black border, white for 1.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace vision {

// An unknown family name or an id outside a family. The message names the
// value and what was expected (the accepted names, or the id range).
class MarkerFamilyError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

class MarkerFamily {
 public:
  // The name of rig's own codebook, the default family of a target.
  static constexpr const char* kDefaultName = "rig4x4";

  // The family of that name (one of names()), built once and shared.
  // Throws MarkerFamilyError naming the value and the accepted names.
  static const MarkerFamily& named(const std::string& name);
  // The accepted names, rig4x4 first.
  static const std::vector<std::string>& names();
  // names() as text for error messages: "\"rig4x4\", \"aruco:DICT_4X4_50\", ...".
  static std::string names_text();

  const std::string& name() const { return name_; }
  int code_cells() const { return code_cells_; }
  int border_cells() const { return border_cells_; }
  int marker_cells() const { return code_cells_ + 2 * border_cells_; }
  // Number of ids; ids are 0 .. size() - 1.
  int size() const { return size_; }
  bool has_id(int id) const { return id >= 0 && id < size_; }
  // Throws MarkerFamilyError "marker id N: expected an id of FAMILY (0 .. M)"
  // unless has_id(id).
  void check_id(int id) const;

  // Whether cell (row, col) of marker `id` is white; border cells are black.
  // Preconditions: has_id(id), 0 <= row, col < marker_cells() (unchecked:
  // it runs per cell of every rendered marker).
  bool cell_is_white(int id, int row, int col) const {
    const int r = row - border_cells_, c = col - border_cells_;
    if (r < 0 || c < 0 || r >= code_cells_ || c >= code_cells_) return false;
    return white_[(static_cast<size_t>(id) * code_cells_ + r) * code_cells_ + c] != 0;
  }

  // A codebook (e.g. with other CodebookOptions) as a family named rig4x4.
  static MarkerFamily from_codebook(const class Codebook& codebook);

  // A family from explicit code grids: `white` holds size x code_cells x
  // code_cells cells, row-major per id, 1 = white. For tests and custom
  // families; std::invalid_argument if the sizes disagree.
  MarkerFamily(std::string name, int code_cells, int border_cells, std::vector<uint8_t> white);

 private:
  std::string name_;
  int code_cells_ = 0;
  int border_cells_ = 0;
  int size_ = 0;
  std::vector<uint8_t> white_;
};

}  // namespace vision
