// The geometry stage of the renderer (see scene_geometry.hpp).
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

}  // namespace

void accumulate_radiance(const RayTable& rays, const SheetArtwork& front, const SheetArtwork& back,
                         const SceneOptions& options, const vision::Pose& T,
                         const cv::Mat& background, float weight, cv::Mat& radiance) {
  const float bg_const = static_cast<float>(options.background_reflectance);
  const bool has_bg_image = !background.empty();
  if (!options.show_target) {
    if (has_bg_image) {
      cv::scaleAdd(background, weight, radiance, radiance);
    } else {
      radiance += cv::Scalar(weight * bg_const);
    }
    return;
  }
  const Eigen::Matrix3d H = plane_from_image(T);
  // The printed side faces the camera when the camera centre is on the -z side
  // of the sheet (z points into the sheet).
  const bool front_side = (-(T.R.transpose() * T.t)).z() < 0;
  const SheetArtwork& sheet = front_side ? front : back;
  const double paper = options.paper_reflectance;
  const double ink = options.ink_reflectance;
  const double dir = options.lighting_direction_deg * M_PI / 180;
  const double gx = options.lighting_gradient_per_m * std::cos(dir);
  const double gy = options.lighting_gradient_per_m * std::sin(dir);
  const int n = options.supersampling;
  const double inv_n = 1.0 / n;
  const double h00 = H(0, 0), h01 = H(0, 1), h02 = H(0, 2);
  const double h10 = H(1, 0), h11 = H(1, 1), h12 = H(1, 2);
  const double h20 = H(2, 0), h21 = H(2, 1), h22 = H(2, 2);
  const int width = rays.width;
  const int height = rays.height;
  const auto illumination = [&](double X, double Y) { return std::max(0.05, 1 + gx * X + gy * Y); };
  const auto background_at = [&](int u, int v) -> double {
    return has_bg_image ? background.ptr<float>(v)[u] : bg_const;
  };

  // A pixel's footprint on the sheet: centre (X, Y) and Jacobian F = d(X, Y)/d(u, v)
  // = d(X, Y)/d(x, y) * d(x, y)/d(u, v). False when the ray misses the sheet plane.
  struct Footprint {
    double X, Y, f00, f01, f10, f11;
  };
  const auto footprint = [&](size_t i, Footprint* f) {
    const double x = rays.x[i], y = rays.y[i];
    const double w = h20 * x + h21 * y + h22;
    if (!(w > 1e-12)) return false;  // parallel to or away from the sheet, or NaN
    const double iw = 1.0 / w;
    f->X = (h00 * x + h01 * y + h02) * iw;
    f->Y = (h10 * x + h11 * y + h12) * iw;
    const double ax = (h00 - f->X * h20) * iw, ay = (h01 - f->X * h21) * iw;
    const double bx = (h10 - f->Y * h20) * iw, by = (h11 - f->Y * h21) * iw;
    f->f00 = ax * rays.j00[i] + ay * rays.j10[i];
    f->f01 = ax * rays.j01[i] + ay * rays.j11[i];
    f->f10 = bx * rays.j00[i] + by * rays.j10[i];
    f->f11 = bx * rays.j01[i] + by * rays.j11[i];
    return true;
  };

  // One pixel, exactly: its footprint's bounding box decides between a uniform
  // region and the supersampled area integral.
  const auto shade_pixel = [&](int u, int v) -> double {
    const size_t i = static_cast<size_t>(v) * static_cast<size_t>(width) + static_cast<size_t>(u);
    Footprint f;
    if (!footprint(i, &f)) return background_at(u, v);
    const double ex = 0.5 * (std::abs(f.f00) + std::abs(f.f01));
    const double ey = 0.5 * (std::abs(f.f10) + std::abs(f.f11));
    switch (sheet.classify(f.X - ex, f.X + ex, f.Y - ey, f.Y + ey)) {
      case Region::kBackground:
        return background_at(u, v);
      case Region::kPaper:
        return paper * illumination(f.X, f.Y);
      case Region::kInk:
        return ink * illumination(f.X, f.Y);
      case Region::kMixed:
        break;
    }
    // n x n sub-pixels, each integrated exactly over the axis-aligned box with
    // the second moments of its footprint parallelogram (x width sqrt(f00^2 + f01^2) / n).
    const double hx = 0.5 * std::hypot(f.f00, f.f01) * inv_n;
    const double hy = 0.5 * std::hypot(f.f10, f.f11) * inv_n;
    double cover_paper = 0, cover_ink = 0;
    for (int sv = 0; sv < n; ++sv) {
      const double dv = (sv + 0.5) * inv_n - 0.5;
      for (int su = 0; su < n; ++su) {
        const double du = (su + 0.5) * inv_n - 0.5;
        const Coverage c =
            sheet.integrate(f.X + f.f00 * du + f.f01 * dv, f.Y + f.f10 * du + f.f11 * dv, hx, hy);
        cover_paper += c.paper;
        cover_ink += c.ink;
      }
    }
    cover_paper *= inv_n * inv_n;
    cover_ink *= inv_n * inv_n;
    return illumination(f.X, f.Y) * (paper * cover_paper + ink * cover_ink) +
           background_at(u, v) * std::max(0.0, 1 - cover_paper - cover_ink);
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
  for (int v0 = 0; v0 < height; v0 += kTile) {
    const int v1 = std::min(v0 + kTile, height) - 1;
    for (int u0 = 0; u0 < width; u0 += kTile) {
      const int u1 = std::min(u0 + kTile, width) - 1;
      const int us[4] = {u0, u1, u0, u1};
      const int vs[4] = {v0, v0, v1, v1};
      Footprint c[4];
      bool all_hit = true;
      double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
      for (int k = 0; k < 4 && all_hit; ++k) {
        all_hit = footprint(
            static_cast<size_t>(vs[k]) * static_cast<size_t>(width) + static_cast<size_t>(us[k]),
            &c[k]);
        if (!all_hit) break;
        const double ex = std::abs(c[k].f00) + std::abs(c[k].f01);
        const double ey = std::abs(c[k].f10) + std::abs(c[k].f11);
        x0 = std::min(x0, c[k].X - ex);
        x1 = std::max(x1, c[k].X + ex);
        y0 = std::min(y0, c[k].Y - ey);
        y1 = std::max(y1, c[k].Y + ey);
      }
      if (all_hit) {
        Footprint m;
        const int um = (u0 + u1) / 2, vm = (v0 + v1) / 2;
        const double fu = u1 > u0 ? static_cast<double>(um - u0) / (u1 - u0) : 0.0;
        const double fv = v1 > v0 ? static_cast<double>(vm - v0) / (v1 - v0) : 0.0;
        all_hit = footprint(
            static_cast<size_t>(vm) * static_cast<size_t>(width) + static_cast<size_t>(um), &m);
        const auto bilinear = [&](double a00, double a10, double a01, double a11) {
          return (1 - fv) * ((1 - fu) * a00 + fu * a10) + fv * ((1 - fu) * a01 + fu * a11);
        };
        all_hit = all_hit &&
                  std::abs(m.X - bilinear(c[0].X, c[1].X, c[2].X, c[3].X)) <=
                      0.5 * (std::abs(m.f00) + std::abs(m.f01)) &&
                  std::abs(m.Y - bilinear(c[0].Y, c[1].Y, c[2].Y, c[3].Y)) <=
                      0.5 * (std::abs(m.f10) + std::abs(m.f11));
      }
      const Region region = all_hit ? sheet.classify(x0, x1, y0, y1) : Region::kMixed;
      if (region == Region::kMixed) {
        for (int v = v0; v <= v1; ++v) {
          float* out = radiance.ptr<float>(v);
          for (int u = u0; u <= u1; ++u)
            out[u] += static_cast<float>(weight * shade_pixel(u, v));
        }
        continue;
      }
      if (region == Region::kBackground) {
        for (int v = v0; v <= v1; ++v) {
          float* out = radiance.ptr<float>(v);
          for (int u = u0; u <= u1; ++u)
            out[u] += static_cast<float>(weight * background_at(u, v));
        }
        continue;
      }
      // Uniform paper or ink: the illumination is affine on the sheet, and
      // bilinear interpolation between the tile's corners follows it to
      // well below the sensor's noise.
      const double reflectance = weight * (region == Region::kInk ? ink : paper);
      const double l00 = illumination(c[0].X, c[0].Y), l10 = illumination(c[1].X, c[1].Y);
      const double l01 = illumination(c[2].X, c[2].Y), l11 = illumination(c[3].X, c[3].Y);
      const double su = u1 > u0 ? 1.0 / (u1 - u0) : 0.0;
      const double sv = v1 > v0 ? 1.0 / (v1 - v0) : 0.0;
      for (int v = v0; v <= v1; ++v) {
        float* out = radiance.ptr<float>(v);
        const double fv = (v - v0) * sv;
        const double left = l00 + fv * (l01 - l00), right = l10 + fv * (l11 - l10);
        for (int u = u0; u <= u1; ++u) {
          const double fu = (u - u0) * su;
          out[u] += static_cast<float>(reflectance * (left + fu * (right - left)));
        }
      }
    }
  }
}

}  // namespace sim::scene::detail
