// Exact box integrals over the printed sheet (see sheet.hpp).
#include "sheet.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace sim::scene::detail {

namespace {

double overlap(double a0, double a1, double b0, double b1) {
  return std::max(0.0, std::min(a1, b1) - std::max(a0, b0));
}

}  // namespace

SheetArtwork::SheetArtwork(const vision::Target& target, const vision::MarkerFamily& family,
                           bool show_markers)
    : sx0_(target.sheet_origin_m.x()),
      sx1_(target.sheet_origin_m.x() + target.sheet_width_m),
      sy0_(target.sheet_origin_m.y()),
      sy1_(target.sheet_origin_m.y() + target.sheet_height_m) {
  if (!show_markers) return;
  for (const vision::TargetMarker& tm : target.markers) {
    if (!family.has_id(tm.id)) {
      throw std::invalid_argument("SceneRenderer: target marker id " + std::to_string(tm.id) +
                                  " is not in " + family.name() + " (ids 0 .. " +
                                  std::to_string(family.size() - 1) + ")");
    }
    Marker m;
    m.n = family.marker_cells();
    m.cell = tm.side_m / m.n;
    m.inv_cell = 1.0 / m.cell;
    m.x0 = tm.centre_m.x() - tm.side_m / 2;
    m.y0 = tm.centre_m.y() - tm.side_m / 2;
    m.x1 = m.x0 + tm.side_m;
    m.y1 = m.y0 + tm.side_m;
    const int n = m.n, w = n + 1;
    m.black.assign(static_cast<size_t>(n * n), 0);
    m.sat.assign(static_cast<size_t>(w * w), 0.0f);
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) {
        const uint8_t ink = family.cell_is_white(tm.id, r, c) ? 0 : 1;
        m.black[static_cast<size_t>(r * n + c)] = ink;
        m.sat[static_cast<size_t>((r + 1) * w + c + 1)] =
            m.sat_at(r, c + 1) + m.sat_at(r + 1, c) - m.sat_at(r, c) + ink;
      }
    }
    markers_.push_back(m);
  }
}

double SheetArtwork::black_cells(const Marker& m, double u0, double u1, double v0, double v1) {
  const double kN = m.n;
  u0 = std::clamp(u0, 0.0, kN);
  u1 = std::clamp(u1, 0.0, kN);
  v0 = std::clamp(v0, 0.0, kN);
  v1 = std::clamp(v1, 0.0, kN);
  if (u1 <= u0 || v1 <= v0) return 0;
  // I(u, v) = integral of the black indicator over [0, u] x [0, v]: bilinear in
  // the SAT, exact because the cells are constant.
  const auto I = [&m](double u, double v) {
    const int iu = std::min(static_cast<int>(u), m.n - 1);
    const int iv = std::min(static_cast<int>(v), m.n - 1);
    const double fu = u - iu;
    const double fv = v - iv;
    const double s00 = m.sat_at(iv, iu);
    const double s01 = m.sat_at(iv, iu + 1);
    const double s10 = m.sat_at(iv + 1, iu);
    return s00 + fu * (s01 - s00) + fv * (s10 - s00) +
           fu * fv * m.black[static_cast<size_t>(iv * m.n + iu)];
  };
  return I(u1, v1) - I(u0, v1) - I(u1, v0) + I(u0, v0);
}

Coverage SheetArtwork::integrate(double cx, double cy, double hx, double hy) const {
  const double x0 = cx - hx, x1 = cx + hx, y0 = cy - hy, y1 = cy + hy;
  const double inv_area = 1.0 / ((x1 - x0) * (y1 - y0));
  const double on_sheet = overlap(x0, x1, sx0_, sx1_) * overlap(y0, y1, sy0_, sy1_);
  double ink = 0;
  for (const Marker& m : markers_) {
    if (x1 <= m.x0 || x0 >= m.x1 || y1 <= m.y0 || y0 >= m.y1) continue;
    ink += black_cells(m, (x0 - m.x0) * m.inv_cell, (x1 - m.x0) * m.inv_cell,
                       (y0 - m.y0) * m.inv_cell, (y1 - m.y0) * m.inv_cell) *
           m.cell * m.cell;
  }
  return {(on_sheet - ink) * inv_area, ink * inv_area};
}

}  // namespace sim::scene::detail
