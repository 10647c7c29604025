// The printed sheet as the renderer sees it: exact area integrals of the
// reflectance over axis-aligned boxes of the target plane (private to sim_scene).
#pragma once

#include <array>
#include <vector>

#include "vision/marker_family.hpp"
#include "vision/target.hpp"

namespace sim::scene::detail {

// Area fractions of a box covered by white paper and by ink; the rest
// (1 - paper - ink) lies off the sheet.
struct Coverage {
  double paper = 0;
  double ink = 0;
};

enum class Region { kBackground, kPaper, kInk, kMixed };

class SheetArtwork {
 public:
  // show_markers false draws the sheet blank (its back, seen from behind).
  SheetArtwork(const vision::Target& target, const vision::MarkerFamily& family, bool show_markers);

  // What an axis-aligned box [x0, x1] x [y0, y1] (target frame, metres) covers:
  // one uniform region, or kMixed when it straddles an edge.
  // Inline: it runs once per pixel or tile.
  Region classify(double x0, double x1, double y0, double y1) const {
    if (x1 <= sx0_ || x0 >= sx1_ || y1 <= sy0_ || y0 >= sy1_) return Region::kBackground;
    if (x0 < sx0_ || x1 > sx1_ || y0 < sy0_ || y1 > sy1_) return Region::kMixed;
    for (const Marker& m : markers_) {
      if (x1 <= m.x0 || x0 >= m.x1 || y1 <= m.y0 || y0 >= m.y1) continue;
      if (x0 < m.x0 || x1 > m.x1 || y0 < m.y0 || y1 > m.y1) return Region::kMixed;
      const int c0 = static_cast<int>((x0 - m.x0) * m.inv_cell);
      const int c1 = static_cast<int>((x1 - m.x0) * m.inv_cell);
      const int r0 = static_cast<int>((y0 - m.y0) * m.inv_cell);
      const int r1 = static_cast<int>((y1 - m.y0) * m.inv_cell);
      if (c0 != c1 || r0 != r1 || c0 >= m.n || r0 >= m.n) return Region::kMixed;
      return m.black[static_cast<size_t>(r0 * m.n + c0)] ? Region::kInk : Region::kPaper;
    }
    return Region::kPaper;
  }

  // Exact coverage of the box centred at (cx, cy) with half extents hx, hy
  // (metres, > 0). The marker cells are integrated through a summed-area table
  // of each marker's n x n grid (n = the family's marker_cells()), whose bilinear interpolation is
  // the exact integral of the piecewise-constant cells (no resolution limit).
  Coverage integrate(double cx, double cy, double hx, double hy) const;

 private:
  struct Marker {
    double x0 = 0, y0 = 0;  // top-left corner of the black square, metres
    double x1 = 0, y1 = 0;  // bottom-right corner
    double cell = 0, inv_cell = 0;
    int n = 0;                   // cells per side
    std::vector<float> sat;      // (n + 1)^2: black cells in rows < r, cols < c
    std::vector<uint8_t> black;  // n^2, row-major: 1 = ink
    float sat_at(int r, int c) const { return sat[static_cast<size_t>(r * (n + 1) + c)]; }
  };
  // The black area (in cells^2) of a marker inside [u0, u1] x [v0, v1] (cells).
  static double black_cells(const Marker& m, double u0, double u1, double v0, double v1);

  double sx0_, sx1_, sy0_, sy1_;  // the sheet, target frame, metres
  std::vector<Marker> markers_;
};

}  // namespace sim::scene::detail
