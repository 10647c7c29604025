// vision::artwork: printable markers and target sheets at true physical size,
// drawn with cairo (SVG, PDF or PNG chosen by the file extension).
//
// Sizes: SVG and PDF pages are in points (1 pt = 25.4 / 72 mm) and carry the
// exact physical size; a PNG is rendered at `dpi` pixels per inch, its pixel
// size is round(size_mm / 25.4 * dpi) and its pHYs chunk is not relied upon.
// Print at 100 % ("actual size"), never "fit to page".
//
// Marker artwork (see vision/marker_family.hpp for the cells): the n x n
// cells of side s / n of the marker's family (6 x 6 for rig4x4), black border, code cells white for
// bit 1, surrounded by a white quiet zone of quiet_cells cells. The id and size are printed small
// in grey in the outer half of the bottom quiet zone (omitted when the quiet zone is too narrow to
// hold legible text away from the border, i.e. under ~3 mm).
#pragma once

#include <stdexcept>
#include <string>

#include "vision/codebook.hpp"
#include "vision/marker_family.hpp"
#include "vision/target.hpp"

namespace vision {

// A file that cannot be written, an unknown extension, or an id/size out of
// range. The message names the file or the value and what was expected.
class ArtworkError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class ArtworkFormat { kSvg, kPdf, kPng };

// The format of a path from its extension (.svg, .pdf, .png, case-insensitive).
// Throws ArtworkError for anything else.
ArtworkFormat artwork_format_from_path(const std::string& path);

struct MarkerArtworkOptions {
  double side_mm = 50.0;  // outer side of the black border, > 0
  int quiet_cells = 1;    // white margin around the border, cells (>= 0)
  double dpi = 600.0;     // PNG only: pixels per inch, in [10, 4800]
  bool label = true;      // print "id N  50 mm" in the quiet zone
};

// Writes marker `id` of the codebook as a single page of side
// side_mm * (6 + 2 * quiet_cells) / 6. Throws ArtworkError.
void write_marker_artwork(const Codebook& codebook, int id, const MarkerArtworkOptions& options,
                          const std::string& path);
// The same for marker `id` of any family: a page of side
// side_mm * (n + 2 * quiet_cells) / n, n = family.marker_cells().
void write_marker_artwork(const MarkerFamily& family, int id, const MarkerArtworkOptions& options,
                          const std::string& path);

struct TargetArtworkOptions {
  double dpi = 300.0;  // PNG only: pixels per inch, in [10, 4800]
  bool label = true;   // print each marker's id and size, and the sheet's name
};

// Writes the whole sheet of a target (its sheet_width_m x sheet_height_m page;
// markers at their centres relative to sheet_origin_m, quiet zones white).
// Throws ArtworkError (or TargetError if an id is not in the codebook).
// This overload needs a rig4x4 target (TargetError otherwise).
void write_target_artwork(const Codebook& codebook, const Target& target,
                          const TargetArtworkOptions& options, const std::string& path);
// The sheet in the target's own family (Target::family).
void write_target_artwork(const Target& target, const TargetArtworkOptions& options,
                          const std::string& path);
void write_target_artwork(const MarkerFamily& family, const Target& target,
                          const TargetArtworkOptions& options, const std::string& path);

}  // namespace vision
