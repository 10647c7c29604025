// Identification: the 6x6 cell grid read through the homography of the refined
// corners (Maidi et al. 2010, eq. 30) and decoded in four orientations.
//
// The homography maps marker cell coordinates (u, v) in [0, 6]^2 (u along
// A->B, v along A->D of the candidate) to the undistorted normalized plane,
// where a plane's image is exactly projective; each sample point is then
// distorted into the image. Computing eq. 30 in distorted pixels instead
// would misplace cells by up to a few pixels on large markers near the image
// border.
#include <Eigen/LU>
#include <algorithm>

#include "detector_internal.hpp"
#include "lens_model.hpp"

namespace vision::detail {
namespace {

class GridReader {
 public:
  GridReader(const cv::Mat& gray, const Camera& camera, const Eigen::Matrix3d& H)
      : gray_(gray), camera_(camera), H_(H) {}

  // Image position of marker cell coordinates (u, v); false outside the image.
  bool pixel(double u, double v, Eigen::Vector2d* px) const {
    const Eigen::Vector3d x = H_ * Eigen::Vector3d(u, v, 1);
    if (!(x.z() > 0)) return false;
    *px = distort_normalized(camera_, x.head<2>() / x.z());
    return inside_image(gray_, *px, 0);
  }

  // Mean of a 3x3 lattice spanning `fraction` of the cell centred at (u, v).
  bool mean(double u, double v, double fraction, double* value) const {
    double sum = 0;
    for (int a = -1; a <= 1; ++a)
      for (int b = -1; b <= 1; ++b) {
        Eigen::Vector2d px;
        if (!pixel(u + 0.5 * fraction * a, v + 0.5 * fraction * b, &px)) return false;
        sum += sample_bilinear(gray_, px.x(), px.y());
      }
    *value = sum / 9;
    return true;
  }

 private:
  const cv::Mat& gray_;
  const Camera& camera_;
  Eigen::Matrix3d H_;
};

// Mean grey level of each of the 6x6 cells, rows along A->D, columns along A->B.
using CellLevels = std::array<std::array<double, kMarkerCells>, kMarkerCells>;

bool is_border_cell(int r, int c) {
  return r == 0 || c == 0 || r == kMarkerCells - 1 || c == kMarkerCells - 1;
}

// Every cell's level, and the black reference: the mean of the border cells.
// False when a cell leaves the image.
bool read_cells(const GridReader& grid, double fraction, CellLevels* cells, double* black) {
  *black = 0;
  for (int r = 0; r < kMarkerCells; ++r)
    for (int c = 0; c < kMarkerCells; ++c) {
      if (!grid.mean(c + 0.5, r + 0.5, fraction, &(*cells)[r][c])) return false;
      if (is_border_cell(r, c)) *black += (*cells)[r][c];
    }
  *black /= 4 * (kMarkerCells - 1);
  return true;
}

// The quiet zone's levels half a cell outside each side, wherever they fall
// inside the image.
std::vector<double> read_quiet_zone(const GridReader& grid, double fraction) {
  std::vector<double> outside;
  for (int k = 0; k < kMarkerCells; ++k) {
    const double m = k + 0.5, out_lo = -0.5, out_hi = kMarkerCells + 0.5;
    for (const auto& uv : {Eigen::Vector2d(m, out_lo), Eigen::Vector2d(out_hi, m),
                           Eigen::Vector2d(m, out_hi), Eigen::Vector2d(out_lo, m)}) {
      double v;
      if (grid.mean(uv.x(), uv.y(), 0.5 * fraction, &v)) outside.push_back(v);
    }
  }
  return outside;
}

// The quiet zone must be white all round, and right up to each corner: an
// occluder that only grazes a corner leaves the sides' edges intact but
// darkens (or, if grey, fails to whiten) the paper beside the corner.
bool quiet_zone_is_white(const GridReader& grid, const std::vector<double>& outside,
                         double min_white) {
  for (double v : outside)
    if (v < min_white) return false;
  constexpr double kAcross = 0.35, kAlong = 0.3;  // cells, inside the one-cell quiet zone
  for (const auto& corner :
       {Eigen::Vector2d(0, 0), Eigen::Vector2d(kMarkerCells, 0),
        Eigen::Vector2d(kMarkerCells, kMarkerCells), Eigen::Vector2d(0, kMarkerCells)}) {
    const double su = corner.x() > 0 ? 1 : -1, sv = corner.y() > 0 ? 1 : -1;  // outward
    for (const auto& probe :
         {Eigen::Vector2d(corner.x() + su * kAcross, corner.y() + sv * kAcross),
          Eigen::Vector2d(corner.x() + su * kAcross, corner.y() - sv * kAlong),
          Eigen::Vector2d(corner.x() - su * kAlong, corner.y() + sv * kAcross)}) {
      double v;
      if (grid.mean(probe.x(), probe.y(), 0.2, &v) && v < min_white) return false;
    }
  }
  return true;
}

// Border cells not clearly black (within `margin` of the threshold or above).
int border_errors(const CellLevels& cells, double threshold, double margin) {
  int errors = 0;
  for (int r = 0; r < kMarkerCells; ++r)
    for (int c = 0; c < kMarkerCells; ++c)
      if (is_border_cell(r, c) && cells[r][c] > threshold - margin) ++errors;
  return errors;
}

// The code cells decoded, with `id`'s contrast kept; none when the code is not
// in the codebook or needs more corrections than allowed.
std::optional<Identification> decode_cells(const CellLevels& cells, double threshold, double margin,
                                           const Codebook& codebook, const DetectorParameters& p,
                                           Identification id) {
  uint16_t bits = 0, uncertain = 0;
  for (int r = 0; r < kCodeCells; ++r)
    for (int c = 0; c < kCodeCells; ++c) {
      const double v = cells[r + 1][c + 1];
      const auto bit = static_cast<uint16_t>(1u << Codebook::bit_index(r, c));
      if (v > threshold) bits |= bit;
      if (std::abs(v - threshold) < margin) uncertain |= bit;
    }
  const auto decoded = codebook.decode(bits);
  if (!decoded) return std::nullopt;
  // An uncertain cell read right is still a guess: it counts as corrected.
  const uint16_t expected =
      Codebook::rotate_clockwise(codebook.code(decoded->id), decoded->rotation);
  const int corrected =
      Codebook::hamming_distance(0, static_cast<uint16_t>((bits ^ expected) | uncertain));
  const int max_corrected = p.max_bits_corrected < 0
                                ? codebook.max_correction_bits()
                                : std::min(p.max_bits_corrected, codebook.max_correction_bits());
  if (corrected > max_corrected) return std::nullopt;
  id.id = decoded->id;
  id.rotation = decoded->rotation;
  id.bits_corrected = corrected;
  return id;
}

}  // namespace

Eigen::Matrix3d square_homography(const std::array<Eigen::Vector2d, 4>& x, double side) {
  const double s = side;
  const Eigen::Vector2d uv[4] = {{0, 0}, {s, 0}, {s, s}, {0, s}};
  Eigen::Matrix<double, 8, 8> a;
  Eigen::Matrix<double, 8, 1> b;
  for (int i = 0; i < 4; ++i) {
    const double u = uv[i].x(), v = uv[i].y(), X = x[i].x(), Y = x[i].y();
    a.row(2 * i) << u, v, 1, 0, 0, 0, -u * X, -v * X;
    a.row(2 * i + 1) << 0, 0, 0, u, v, 1, -u * Y, -v * Y;
    b(2 * i) = X;
    b(2 * i + 1) = Y;
  }
  const Eigen::Matrix<double, 8, 1> h = a.partialPivLu().solve(b);
  Eigen::Matrix3d H;
  H << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), 1;
  return H;
}

std::optional<Identification> identify(const cv::Mat& gray, const Camera& camera,
                                       const EdgeFit& fit, const Codebook& codebook,
                                       const DetectorParameters& p) {
  const GridReader grid(gray, camera, square_homography(fit.corners_norm, kMarkerCells));
  CellLevels cells;
  double black = 0;
  if (!read_cells(grid, p.cell_sample_fraction, &cells, &black)) return std::nullopt;

  // The white reference: the quiet zone, half a cell outside each side
  // (median, so that a stray dark spot in it does not pull the threshold).
  std::vector<double> outside = read_quiet_zone(grid, p.cell_sample_fraction);
  if (outside.size() < 8) return std::nullopt;
  std::nth_element(outside.begin(), outside.begin() + outside.size() / 2, outside.end());
  const double white = outside[outside.size() / 2];

  Identification id;
  id.contrast = white - black;
  if (id.contrast < p.min_contrast) return std::nullopt;
  if (!quiet_zone_is_white(grid, outside, black + p.min_quiet_zone_level * id.contrast))
    return std::nullopt;
  const double threshold = 0.5 * (white + black);
  const double margin = p.min_cell_margin * id.contrast;
  if (border_errors(cells, threshold, margin) > p.max_border_errors) return std::nullopt;
  return decode_cells(cells, threshold, margin, codebook, p, id);
}

}  // namespace vision::detail
