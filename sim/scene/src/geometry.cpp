// The geometry stage of the renderer (see geometry.hpp).
#include "geometry.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace sim::scene::detail {

namespace {

// The sheet plane maps to the camera by M = [r1 r2 t]: lambda (x, y, 1) =
// M (X, Y, 1). Its inverse takes an undistorted normalized point to the sheet.
Eigen::Matrix3d plane_from_image(const vision::Pose& T_cam_target) {
  Eigen::Matrix3d M;
  M.col(0) = T_cam_target.R.col(0);
  M.col(1) = T_cam_target.R.col(1);
  M.col(2) = T_cam_target.t;
  return M.inverse();
}

// Adds weight x the background alone (no sheet in the scene).
void accumulate_background(const SceneOptions& options, const cv::Mat& background, float weight,
                           cv::Mat& radiance) {
  if (!background.empty()) {
    cv::scaleAdd(background, weight, radiance, radiance);
  } else {
    radiance += cv::Scalar(weight * static_cast<float>(options.background_reflectance));
  }
}

// A pixel's footprint on the sheet: centre (X, Y) and Jacobian F = d(X, Y)/d(u, v)
// = d(X, Y)/d(x, y) * d(x, y)/d(u, v).
struct Footprint {
  double X, Y, f00, f01, f10, f11;
};

// Tiles of kTile x kTile pixels: when the footprint of the whole tile lies in
// one uniform region (most of the image), it is filled without per-pixel
// geometry. The tile's footprint is bounded by the box of its four corner
// pixels' centres grown by twice their pixel footprints, which holds while
// the mapping is close to bilinear over the tile (perspective and lens
// curvature: ~1 % of a footprint at 40 degrees of tilt). The tile's centre
// pixel checks that: if it departs from the bilinear prediction by more
// than half a footprint (grazing views near the horizon), the tile is
// shaded pixel by pixel.
constexpr int kTile = 8;

// A tile: pixels [u0, u1] x [v0, v1], and the footprints of its corner
// pixels (u0, v0), (u1, v0), (u0, v1), (u1, v1) once known.
struct Tile {
  int u0, u1, v0, v1;
  Footprint corners[4];
};

// What a pixel of the sheet reflects: the diffuse radiance (reflectance x
// illumination, or the background) and the gloss its area carries (the
// specular weight of the glare lobe: paper_gloss x paper area + ink_gloss x
// ink area).
struct Shade {
  double diffuse = 0;
  double gloss = 0;
};

// The glare lobe over the image (SceneOptions::glare_peak): a function of the
// pixel's ray only (a distant lamp). It varies over ~fx * glare_lobe_deg
// pixels (~100 px), so a tile takes it bilinearly from its corners: the
// error of that, (8 px)^2 / 8 x its curvature (peak / (100 px)^2), is below
// 1e-3 of the peak, a tenth of a grey level.
class GlareLobe {
 public:
  GlareLobe(const SceneOptions& o, const vision::Pose& T, bool front_side) {
    on_ = front_side && o.glare_peak > 0;
    if (!on_) return;
    const double tilt = o.glare_light_tilt_deg * M_PI / 180;
    const double azimuth = o.glare_light_azimuth_deg * M_PI / 180;
    // The ray from the camera that meets the lamp's mirror image, target frame:
    // minus the mirror of the lamp's direction about the front normal -z.
    const Eigen::Vector3d ray_target(std::sin(tilt) * std::cos(azimuth),
                                     std::sin(tilt) * std::sin(azimuth), std::cos(tilt));
    s_ = T.R * ray_target;
    const double sigma = o.glare_lobe_deg * M_PI / 180;
    inv_sigma2_ = 1 / (sigma * sigma);
    peak_ = o.glare_peak;
  }
  bool on() const { return on_; }
  // The lobe (times glare_peak) seen along the normalized image point (x, y).
  double operator()(double x, double y) const {
    const double cosine = (x * s_.x() + y * s_.y() + s_.z()) / std::sqrt(x * x + y * y + 1);
    const double exponent = (1 - cosine) * inv_sigma2_;
    return exponent > 30 ? 0.0 : peak_ * std::exp(-exponent);
  }

 private:
  bool on_ = false;
  Eigen::Vector3d s_ = Eigen::Vector3d::UnitZ();
  double inv_sigma2_ = 0, peak_ = 0;
};

// The sheet side facing the camera as the pixels see it under one pose.
class SheetView {
 public:
  SheetView(const RayTable& rays, const SheetArtwork& sheet, const SceneOptions& options,
            const SheetBow& bow, const vision::Pose& T, bool front_side, const cv::Mat& background)
      : rays_(rays),
        sheet_(sheet),
        bow_(bow),
        glare_(options, T, front_side),
        camera_in_target_(-(T.R.transpose() * T.t)),
        background_(background),
        has_bg_image_(!background.empty()),
        bg_const_(static_cast<float>(options.background_reflectance)),
        paper_(options.paper_reflectance),
        ink_(options.ink_reflectance),
        paper_gloss_(options.paper_gloss),
        ink_gloss_(options.ink_gloss),
        n_(options.supersampling),
        inv_n_(1.0 / n_),
        H_(plane_from_image(T)),
        h00_(H_(0, 0)),
        h01_(H_(0, 1)),
        h02_(H_(0, 2)),
        h10_(H_(1, 0)),
        h11_(H_(1, 1)),
        h12_(H_(1, 2)),
        h20_(H_(2, 0)),
        h21_(H_(2, 1)),
        h22_(H_(2, 2)),
        gx_(options.lighting_gradient_per_m * std::cos(lighting_direction_rad(options))),
        gy_(options.lighting_gradient_per_m * std::sin(lighting_direction_rad(options))) {}

  // Adds weight x the radiance of every pixel of the tile at (u0, v0).
  void accumulate_tile(int u0, int v0, float weight, cv::Mat& radiance) const {
    Tile tile;  // the corners' footprints are filled by tile_region
    tile.u0 = u0;
    tile.u1 = std::min(u0 + kTile, rays_.width) - 1;
    tile.v0 = v0;
    tile.v1 = std::min(v0 + kTile, rays_.height) - 1;
    const Region region = tile_region(tile);
    if (region == Region::kMixed) {
      const TileLobe lobe = tile_lobe(tile);
      for (int v = tile.v0; v <= tile.v1; ++v) {
        float* out = radiance.ptr<float>(v);
        for (int u = tile.u0; u <= tile.u1; ++u) {
          const Shade shade = shade_pixel(u, v);
          const double glare = shade.gloss > 0 ? shade.gloss * lobe.at(u, v) : 0.0;
          out[u] += static_cast<float>(weight * (shade.diffuse + glare));
        }
      }
    } else if (region == Region::kBackground) {
      for (int v = tile.v0; v <= tile.v1; ++v) {
        float* out = radiance.ptr<float>(v);
        for (int u = tile.u0; u <= tile.u1; ++u)
          out[u] += static_cast<float>(weight * background_at(u, v));
      }
    } else {
      const bool ink = region == Region::kInk;
      accumulate_uniform(tile, weight * (ink ? ink_ : paper_), radiance);
      if (glare_.on()) accumulate_glare(tile, weight * (ink ? ink_gloss_ : paper_gloss_), radiance);
    }
  }

 private:
  // The glare lobe at a tile's corner pixels, bilinear in between (GlareLobe).
  struct TileLobe {
    int u0 = 0, v0 = 0;
    double su = 0, sv = 0;                      // 1 / (u1 - u0), 1 / (v1 - v0), or 0
    double l00 = 0, l10 = 0, l01 = 0, l11 = 0;  // at (u0, v0), (u1, v0), (u0, v1), (u1, v1)
    double at(int u, int v) const {
      const double fu = (u - u0) * su, fv = (v - v0) * sv;
      return (1 - fv) * ((1 - fu) * l00 + fu * l10) + fv * ((1 - fu) * l01 + fu * l11);
    }
  };
  TileLobe tile_lobe(const Tile& tile) const {
    TileLobe t;
    if (!glare_.on()) return t;
    t.u0 = tile.u0;
    t.v0 = tile.v0;
    t.su = tile.u1 > tile.u0 ? 1.0 / (tile.u1 - tile.u0) : 0.0;
    t.sv = tile.v1 > tile.v0 ? 1.0 / (tile.v1 - tile.v0) : 0.0;
    const auto lobe = [this](int u, int v) {
      const size_t i =
          static_cast<size_t>(v) * static_cast<size_t>(rays_.width) + static_cast<size_t>(u);
      const double x = rays_.x[i], y = rays_.y[i];
      return std::isfinite(x) ? glare_(x, y) : 0.0;
    };
    t.l00 = lobe(tile.u0, tile.v0);
    t.l10 = lobe(tile.u1, tile.v0);
    t.l01 = lobe(tile.u0, tile.v1);
    t.l11 = lobe(tile.u1, tile.v1);
    return t;
  }

  void accumulate_glare(const Tile& tile, double gloss, cv::Mat& radiance) const {
    const TileLobe lobe = tile_lobe(tile);
    for (int v = tile.v0; v <= tile.v1; ++v) {
      float* out = radiance.ptr<float>(v);
      for (int u = tile.u0; u <= tile.u1; ++u)
        out[u] += static_cast<float>(gloss * lobe.at(u, v));
    }
  }

  static double lighting_direction_rad(const SceneOptions& options) {
    return options.lighting_direction_deg * M_PI / 180;
  }

  double illumination(double X, double Y) const { return std::max(0.05, 1 + gx_ * X + gy_ * Y); }

  double background_at(int u, int v) const {
    return has_bg_image_ ? background_.ptr<float>(v)[u] : bg_const_;
  }

  // False when the ray of pixel (u, v) misses the sheet plane.
  bool footprint(int u, int v, Footprint* f) const {
    const size_t i =
        static_cast<size_t>(v) * static_cast<size_t>(rays_.width) + static_cast<size_t>(u);
    const double x = rays_.x[i], y = rays_.y[i];
    const double w = h20_ * x + h21_ * y + h22_;
    if (!(w > 1e-12)) return false;  // parallel to or away from the sheet, or NaN
    const double iw = 1.0 / w;
    f->X = (h00_ * x + h01_ * y + h02_) * iw;
    f->Y = (h10_ * x + h11_ * y + h12_) * iw;
    const double ax = (h00_ - f->X * h20_) * iw, ay = (h01_ - f->X * h21_) * iw;
    const double bx = (h10_ - f->Y * h20_) * iw, by = (h11_ - f->Y * h21_) * iw;
    f->f00 = ax * rays_.j00[i] + ay * rays_.j10[i];
    f->f01 = ax * rays_.j01[i] + ay * rays_.j11[i];
    f->f10 = bx * rays_.j00[i] + by * rays_.j10[i];
    f->f11 = bx * rays_.j01[i] + by * rays_.j11[i];
    if (bow_.on()) raise_onto_bow(f);
    return true;
  }

  // Moves a footprint on the plane z = 0 to where its ray meets the bowed
  // sheet z = -h(X, Y). Along the ray from the camera centre O, the plane
  // z = c is met at O + k (P0 - O) with k = (c - O.z) / (0 - O.z); each step
  // takes c = -h at the last point. The error shrinks by the sheet's slope
  // times the ray's tangent to it (< 0.05 x 1 for a sag of 2 mm over A4 at 45
  // degrees) per step: three steps leave < 1e-4 of the sag. The footprint's
  // Jacobian scales by k (that of the parallel plane; the slope's share, of
  // the same small order, is left out: it only sizes the area integrals).
  void raise_onto_bow(Footprint* f) const {
    const Eigen::Vector3d& o = camera_in_target_;
    if (!(o.z() < 0)) return;  // the back of the sheet: drawn flat
    const double x0 = f->X, y0 = f->Y;
    double k = 1;
    for (int step = 0; step < 3; ++step) {
      k = (-bow_(f->X, f->Y) - o.z()) / -o.z();
      f->X = o.x() + k * (x0 - o.x());
      f->Y = o.y() + k * (y0 - o.y());
    }
    f->f00 *= k;
    f->f01 *= k;
    f->f10 *= k;
    f->f11 *= k;
  }

  // One pixel, exactly: its footprint's bounding box decides between a uniform
  // region and the supersampled area integral.
  Shade shade_pixel(int u, int v) const {
    Footprint f;
    if (!footprint(u, v, &f)) return {background_at(u, v), 0};
    const double ex = 0.5 * (std::abs(f.f00) + std::abs(f.f01));
    const double ey = 0.5 * (std::abs(f.f10) + std::abs(f.f11));
    switch (sheet_.classify(f.X - ex, f.X + ex, f.Y - ey, f.Y + ey)) {
      case Region::kBackground:
        return {background_at(u, v), 0};
      case Region::kPaper:
        return {paper_ * illumination(f.X, f.Y), paper_gloss_};
      case Region::kInk:
        return {ink_ * illumination(f.X, f.Y), ink_gloss_};
      case Region::kMixed:
        break;
    }
    const Coverage c = supersampled_coverage(f);
    return {illumination(f.X, f.Y) * (paper_ * c.paper + ink_ * c.ink) +
                background_at(u, v) * std::max(0.0, 1 - c.paper - c.ink),
            paper_gloss_ * c.paper + ink_gloss_ * c.ink};
  }

  // n x n sub-pixels, each integrated exactly over the axis-aligned box with
  // the second moments of its footprint parallelogram (x width sqrt(f00^2 + f01^2) / n).
  Coverage supersampled_coverage(const Footprint& f) const {
    const double hx = 0.5 * std::hypot(f.f00, f.f01) * inv_n_;
    const double hy = 0.5 * std::hypot(f.f10, f.f11) * inv_n_;
    Coverage cover;
    for (int sv = 0; sv < n_; ++sv) {
      const double dv = (sv + 0.5) * inv_n_ - 0.5;
      for (int su = 0; su < n_; ++su) {
        const double du = (su + 0.5) * inv_n_ - 0.5;
        const Coverage c =
            sheet_.integrate(f.X + f.f00 * du + f.f01 * dv, f.Y + f.f10 * du + f.f11 * dv, hx, hy);
        cover.paper += c.paper;
        cover.ink += c.ink;
      }
    }
    cover.paper *= inv_n_ * inv_n_;
    cover.ink *= inv_n_ * inv_n_;
    return cover;
  }

  // The one region the tile's footprint lies in (filling tile.corners), or
  // kMixed when it may straddle an edge or a corner ray misses the sheet.
  Region tile_region(Tile& tile) const {
    const int us[4] = {tile.u0, tile.u1, tile.u0, tile.u1};
    const int vs[4] = {tile.v0, tile.v0, tile.v1, tile.v1};
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (int k = 0; k < 4; ++k) {
      const Footprint& c = tile.corners[k];
      if (!footprint(us[k], vs[k], &tile.corners[k])) return Region::kMixed;
      const double ex = std::abs(c.f00) + std::abs(c.f01);
      const double ey = std::abs(c.f10) + std::abs(c.f11);
      x0 = std::min(x0, c.X - ex);
      x1 = std::max(x1, c.X + ex);
      y0 = std::min(y0, c.Y - ey);
      y1 = std::max(y1, c.Y + ey);
    }
    if (!is_bilinear(tile)) return Region::kMixed;
    return sheet_.classify(x0, x1, y0, y1);
  }

  // The centre pixel's footprint is within half a footprint of the bilinear
  // interpolation of the corners' (see kTile).
  bool is_bilinear(const Tile& tile) const {
    const Footprint* c = tile.corners;
    Footprint m;
    const int um = (tile.u0 + tile.u1) / 2, vm = (tile.v0 + tile.v1) / 2;
    const double fu =
        tile.u1 > tile.u0 ? static_cast<double>(um - tile.u0) / (tile.u1 - tile.u0) : 0.0;
    const double fv =
        tile.v1 > tile.v0 ? static_cast<double>(vm - tile.v0) / (tile.v1 - tile.v0) : 0.0;
    if (!footprint(um, vm, &m)) return false;
    const auto bilinear = [&](double a00, double a10, double a01, double a11) {
      return (1 - fv) * ((1 - fu) * a00 + fu * a10) + fv * ((1 - fu) * a01 + fu * a11);
    };
    return std::abs(m.X - bilinear(c[0].X, c[1].X, c[2].X, c[3].X)) <=
               0.5 * (std::abs(m.f00) + std::abs(m.f01)) &&
           std::abs(m.Y - bilinear(c[0].Y, c[1].Y, c[2].Y, c[3].Y)) <=
               0.5 * (std::abs(m.f10) + std::abs(m.f11));
  }

  // Uniform paper or ink: the illumination is affine on the sheet, and
  // bilinear interpolation between the tile's corners follows it to
  // well below the sensor's noise.
  void accumulate_uniform(const Tile& tile, double reflectance, cv::Mat& radiance) const {
    const Footprint* c = tile.corners;
    const double l00 = illumination(c[0].X, c[0].Y), l10 = illumination(c[1].X, c[1].Y);
    const double l01 = illumination(c[2].X, c[2].Y), l11 = illumination(c[3].X, c[3].Y);
    const double su = tile.u1 > tile.u0 ? 1.0 / (tile.u1 - tile.u0) : 0.0;
    const double sv = tile.v1 > tile.v0 ? 1.0 / (tile.v1 - tile.v0) : 0.0;
    for (int v = tile.v0; v <= tile.v1; ++v) {
      float* out = radiance.ptr<float>(v);
      const double fv = (v - tile.v0) * sv;
      const double left = l00 + fv * (l01 - l00), right = l10 + fv * (l11 - l10);
      for (int u = tile.u0; u <= tile.u1; ++u) {
        const double fu = (u - tile.u0) * su;
        out[u] += static_cast<float>(reflectance * (left + fu * (right - left)));
      }
    }
  }

  const RayTable& rays_;
  const SheetArtwork& sheet_;
  const SheetBow& bow_;
  const GlareLobe glare_;
  const Eigen::Vector3d camera_in_target_;  // the camera centre O, target frame
  const cv::Mat& background_;
  const bool has_bg_image_;
  const float bg_const_;
  const double paper_, ink_;
  const double paper_gloss_, ink_gloss_;
  const int n_;
  const double inv_n_;
  const Eigen::Matrix3d H_;
  const double h00_, h01_, h02_, h10_, h11_, h12_, h20_, h21_, h22_;
  const double gx_, gy_;  // illumination gradient on the sheet, per metre
};

}  // namespace

SheetBow::SheetBow(const SceneOptions& options, const vision::Target& target)
    : sag_(options.bow_sag_m),
      cx_(target.sheet_origin_m.x() + target.sheet_width_m / 2),
      cy_(target.sheet_origin_m.y() + target.sheet_height_m / 2) {
  const double wx = options.bow_shape == SceneOptions::BowShape::kCylinderY ? 0.0
                    : options.bow_shape == SceneOptions::BowShape::kDome    ? 0.5
                                                                            : 1.0;
  const double wy = options.bow_shape == SceneOptions::BowShape::kCylinderX ? 0.0
                    : options.bow_shape == SceneOptions::BowShape::kDome    ? 0.5
                                                                            : 1.0;
  const double half_w = target.sheet_width_m / 2, half_h = target.sheet_height_m / 2;
  ax_ = wx / (half_w * half_w);
  ay_ = wy / (half_h * half_h);
}

void accumulate_radiance(const RayTable& rays, const SheetArtwork& front, const SheetArtwork& back,
                         const SceneOptions& options, const SheetBow& bow, const vision::Pose& T,
                         const cv::Mat& background, float weight, cv::Mat& radiance) {
  if (!options.show_target) {
    accumulate_background(options, background, weight, radiance);
    return;
  }
  // The printed side faces the camera when the camera centre is on the -z side
  // of the sheet (z points into the sheet).
  const bool front_side = (-(T.R.transpose() * T.t)).z() < 0;
  const SheetView view(rays, front_side ? front : back, options, bow, T, front_side, background);
  for (int v0 = 0; v0 < rays.height; v0 += kTile)
    for (int u0 = 0; u0 < rays.width; u0 += kTile)
      view.accumulate_tile(u0, v0, weight, radiance);
}

}  // namespace sim::scene::detail
