// sim::scene::SceneRenderer: ground truth, artwork colours, edge placement, aliasing,
// the noise model and the visibility flags.
#include "sim/scene/renderer.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace sim::scene {
namespace {

const vision::Codebook& codebook() {
  static const vision::Codebook book;
  return book;
}

vision::Pose pose(double distance_m, double yaw_deg, double pitch_deg, double roll_deg,
                  Eigen::Vector2d offset_m = Eigen::Vector2d::Zero()) {
  const double k = M_PI / 180;
  vision::Pose T;
  T.R = (Eigen::AngleAxisd(roll_deg * k, Eigen::Vector3d::UnitZ()) *
         Eigen::AngleAxisd(yaw_deg * k, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(pitch_deg * k, Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
  T.t = Eigen::Vector3d(offset_m.x(), offset_m.y(), distance_m);
  return T;
}

// A scene with only the geometry: no blur, no vignetting, no lighting
// gradient, no noise, so that pixel values are exact area integrals.
SceneOptions geometry_only() {
  SceneOptions o;
  o.blur_sigma_px = 0;
  o.vignetting = 0;
  o.lighting_gradient_per_m = 0;
  o.noise = false;
  return o;
}

const SceneRenderer& geometry_renderer() {
  static const SceneRenderer r(vision::Camera::paper_default(), vision::Target::paper_default(),
                               codebook(), geometry_only());
  return r;
}

double dn_of(double reflectance, const SceneOptions& o) {
  return 255 * o.exposure * reflectance;
}

TEST(SceneRenderer, GroundTruthCornersAreTheCameraProjectionOfTheTargetCorners) {
  const SceneRenderer& r = geometry_renderer();
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::Target target = vision::Target::paper_default();
  const vision::Pose T = pose(0.6, 25, -15, 10, {0.02, -0.01});
  const RenderedFrame frame = r.render(T, 3);
  ASSERT_EQ(frame.markers.size(), target.markers.size());
  for (const MarkerTruth& m : frame.markers) {
    const auto corners = target.corners_m(m.id);
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d expected = camera.project(T * corners[k]);
      EXPECT_EQ(m.corners_px[k], expected) << "marker " << m.id << " corner " << k;
    }
    EXPECT_TRUE(m.fully_visible) << "marker " << m.id;
  }
}

// Each cell's centre, projected, shows the cell's colour: the renderer draws
// the codebook's bits at the places the target and the camera model say.
TEST(SceneRenderer, FrontalRenderShowsEveryMarkerCellInItsColour) {
  SceneOptions o;  // realistic blur, noise, vignetting and lighting
  const SceneRenderer r(vision::Camera::paper_default(), vision::Target::paper_default(),
                        codebook(), o);
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::Target target = vision::Target::paper_default();
  const vision::Pose T = pose(0.45, 0, 0, 0);
  const RenderedFrame frame = r.render(T, 11);
  // Paper ~190 DN, ink ~11 DN; vignetting and lighting change them by < 30 %.
  const double threshold = 0.5 * (dn_of(o.paper_reflectance, o) + dn_of(o.ink_reflectance, o));
  int cells = 0;
  for (const vision::TargetMarker& m : target.markers) {
    const uint16_t bits = codebook().code(m.id);
    const double cell = m.side_m / vision::kMarkerCells;
    for (int row = 0; row < vision::kMarkerCells; ++row) {
      for (int col = 0; col < vision::kMarkerCells; ++col) {
        const Eigen::Vector3d p(m.centre_m.x() - m.side_m / 2 + (col + 0.5) * cell,
                                m.centre_m.y() - m.side_m / 2 + (row + 0.5) * cell, 0);
        const Eigen::Vector2d px = camera.project(T * p);
        const int value = frame.image.at<uint8_t>(static_cast<int>(std::lround(px.y())),
                                                  static_cast<int>(std::lround(px.x())));
        EXPECT_EQ(value > threshold, vision::Codebook::marker_cell_is_white(bits, row, col))
            << "marker " << m.id << " cell " << row << "," << col << " = " << value;
        ++cells;
      }
    }
  }
  EXPECT_EQ(cells, 4 * 36);
}

// Along a pixel row the white area between a point in the quiet zone and a
// point in the black border is the distance to the edge: an area-correct
// renderer puts the edge exactly where the camera model projects it. The
// tolerance, 0.01 px, is 1/7 of the detector's corner target (0.07 px RMS):
// a renderer error below it cannot hide or fake the detector's accuracy.
void expect_left_edge_exact(const vision::Pose& T) {
  const SceneRenderer& r = geometry_renderer();
  const SceneOptions& o = r.options();
  const vision::Camera& camera = r.camera();
  const cv::Mat irr = r.render_irradiance(T, 1);
  const double paper = dn_of(o.paper_reflectance, o), ink = dn_of(o.ink_reflectance, o);
  const auto corners = r.target().corners_m(0);
  const Eigen::Vector2d a = camera.project(T * corners[0]), d = camera.project(T * corners[3]);
  double worst = 0;
  int rows = 0;
  for (int v = static_cast<int>(a.y() + 0.25 * (d.y() - a.y()));
       v < static_cast<int>(a.y() + 0.75 * (d.y() - a.y())); v += 3) {
    // The edge A-D crosses row v at u_edge (bisection on the target's edge).
    double s0 = 0, s1 = 1;
    for (int it = 0; it < 60; ++it) {
      const double s = 0.5 * (s0 + s1);
      const double pv = camera.project(T * ((1 - s) * corners[0] + s * corners[3])).y();
      ((pv < v) == (a.y() < d.y()) ? s0 : s1) = s;
    }
    const double u_edge = camera.project(T * ((1 - s0) * corners[0] + s0 * corners[3])).x();
    const int u_a = static_cast<int>(std::floor(u_edge)) - 4;
    const int u_b = static_cast<int>(std::floor(u_edge)) + 5;
    double white = 0;
    for (int u = u_a; u <= u_b; ++u)
      white += (irr.at<float>(v, u) - ink) / (paper - ink);
    const double error = white - (u_edge - (u_a - 0.5));
    worst = std::max(worst, std::abs(error));
    ++rows;
  }
  EXPECT_GT(rows, 5);
  EXPECT_LT(worst, 0.01) << "worst edge placement error, px";
}

TEST(SceneRenderer, EdgesLieWhereTheCameraModelProjectsThemFrontal) {
  expect_left_edge_exact(pose(0.30, 0, 0, 8));
}

TEST(SceneRenderer, EdgesLieWhereTheCameraModelProjectsThemTiltedFortyDegrees) {
  expect_left_edge_exact(pose(0.30, 40, 10, 8, {-0.05, 0.02}));
  expect_left_edge_exact(pose(0.12, -35, 20, -20));
}

// Grazing views stretch a pixel's footprint along the sheet and curve the
// pixel-to-sheet mapping most: the edge stays exact at 70 degrees.
TEST(SceneRenderer, EdgesLieWhereTheCameraModelProjectsThemAtGrazingSeventyDegrees) {
  expect_left_edge_exact(pose(0.25, 0, 70, 5));
}

// Aliasing: the ink seen in a window around a marker must not depend on where
// the marker falls relative to the pixel grid. Point sampling of a 35 px
// marker (1 m) changes it by ~1 % from one 0.1 px shift to the next; area
// integration keeps it constant to the change of the projection itself
// (< 1e-4 relative over 1 px). The bound 1e-3 separates the two.
// The area, px^2, of the black cells of a marker in the image: each cell's
// outline sampled 16 times per side through the camera model (the lens curves
// the edges: at 0.1 m the straight-corner quadrilateral is 1.6 % off), shoelace.
double projected_ink_area(const SceneRenderer& r, const vision::Pose& T, int id) {
  const vision::TargetMarker& m = r.target().marker(id);
  const double cell = m.side_m / vision::kMarkerCells;
  double area = 0;
  for (int row = 0; row < vision::kMarkerCells; ++row) {
    for (int col = 0; col < vision::kMarkerCells; ++col) {
      if (vision::Codebook::marker_cell_is_white(codebook().code(id), row, col)) continue;
      const Eigen::Vector2d c0(m.centre_m.x() - m.side_m / 2 + col * cell,
                               m.centre_m.y() - m.side_m / 2 + row * cell);
      const Eigen::Vector2d corner[4] = {c0, c0 + Eigen::Vector2d(cell, 0),
                                         c0 + Eigen::Vector2d(cell, cell),
                                         c0 + Eigen::Vector2d(0, cell)};
      std::vector<Eigen::Vector2d> outline;
      for (int k = 0; k < 4; ++k) {
        for (int s = 0; s < 16; ++s) {
          const Eigen::Vector2d p = corner[k] + (corner[(k + 1) % 4] - corner[k]) * (s / 16.0);
          outline.push_back(r.camera().project(T * Eigen::Vector3d(p.x(), p.y(), 0)));
        }
      }
      double twice = 0;
      for (size_t i = 0; i < outline.size(); ++i) {
        const Eigen::Vector2d& a = outline[i];
        const Eigen::Vector2d& b = outline[(i + 1) % outline.size()];
        twice += a.x() * b.y() - b.x() * a.y();
      }
      area += std::abs(twice) / 2;
    }
  }
  return area;
}

void expect_no_aliasing(double distance_m) {
  const SceneRenderer& r = geometry_renderer();
  const SceneOptions& o = r.options();
  const double paper = dn_of(o.paper_reflectance, o), ink = dn_of(o.ink_reflectance, o);
  const double fx = r.camera().intrinsics().fx;
  const auto corners = r.target().corners_m(0);
  std::vector<double> areas;
  double expected = 0;
  for (int k = 0; k < 10; ++k) {
    const double shift_m = 0.1 * k * distance_m / fx;  // 0.1 px steps
    const vision::Pose T = pose(distance_m, 0, 0, 17, {shift_m, 0.3 * shift_m});
    const cv::Mat irr = r.render_irradiance(T, 1);
    // Window: the marker's image grown by half the quiet zone (still white paper).
    Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
    std::vector<Eigen::Vector2d> quad;
    for (const auto& c : corners) {
      quad.push_back(r.camera().project(T * c));
      lo = lo.cwiseMin(quad.back());
      hi = hi.cwiseMax(quad.back());
    }
    const double margin = 0.5 * (hi.x() - lo.x()) / 6 / 1.5;
    double ink_area = 0;
    for (int v = static_cast<int>(lo.y() - margin); v <= static_cast<int>(hi.y() + margin); ++v) {
      for (int u = static_cast<int>(lo.x() - margin); u <= static_cast<int>(hi.x() + margin); ++u) {
        ink_area += (paper - irr.at<float>(v, u)) / (paper - ink);
      }
    }
    areas.push_back(ink_area);
    if (k == 0) expected = projected_ink_area(r, T, 0);
  }
  const auto [min_it, max_it] = std::minmax_element(areas.begin(), areas.end());
  EXPECT_LT((*max_it - *min_it) / expected, 1e-3) << "ink area varies with sub-pixel position";
  EXPECT_NEAR(areas[0] / expected, 1.0, 1e-4) << "ink area differs from the projected cells'";
}

TEST(SceneRenderer, InkAreaDoesNotAliasAtTenCentimetres) {
  expect_no_aliasing(0.10);
}
TEST(SceneRenderer, InkAreaDoesNotAliasAtOneMetre) {
  expect_no_aliasing(1.0);
}

// Noise: a uniform scene of known signal. Expected variance in DN^2:
// (e + read^2) / (e/DN)^2 + 1/12 (rounding to integers, Sheppard), e the
// electrons of the signal. With N = 420k pixels the sample variance has a
// relative standard error sqrt(2 / N) = 0.22 %; the bounds are 5.5 of them.
// The frame's noise comes from a fixed render seed (measured: within 1.4
// standard errors); another seed would fail one of the three checks with
// probability 3 x 3.8e-8.
void expect_noise_matches_model(const SceneOptions& o) {
  const SceneRenderer r(vision::Camera::paper_default(), vision::Target::paper_default(),
                        codebook(), o);
  const RenderedFrame frame = r.render(vision::Pose(), 99);
  cv::Mat f;
  frame.image.convertTo(f, CV_64F);
  cv::Scalar mean, stddev;
  cv::meanStdDev(f, mean, stddev);
  const double n = static_cast<double>(f.total());
  const double signal_dn = dn_of(o.background_reflectance, o);
  const double e_per_dn = o.full_well_electrons / 255;
  const double e = signal_dn * e_per_dn;
  const double var =
      (e + o.read_noise_electrons * o.read_noise_electrons) / (e_per_dn * e_per_dn) + 1.0 / 12;
  EXPECT_NEAR(mean[0], signal_dn, 5.5 * std::sqrt(var / n));
  EXPECT_NEAR(stddev[0] * stddev[0], var, 5.5 * var * std::sqrt(2 / n));
  // Independent pixels: the correlation of horizontal neighbours is 0 within
  // 5.5 standard errors (1 / sqrt(N)).
  const cv::Mat left = f.colRange(0, f.cols - 1) - mean[0], right = f.colRange(1, f.cols) - mean[0];
  const double correlation = left.dot(right) / (n * stddev[0] * stddev[0]);
  EXPECT_NEAR(correlation, 0, 5.5 / std::sqrt(n));
}

TEST(SceneRenderer, ShotNoiseMatchesThePoissonModel) {
  SceneOptions o;
  o.show_target = false;
  o.vignetting = 0;
  o.background_reflectance = 0.7;  // 161 DN, 12600 e-: shot noise dominates
  expect_noise_matches_model(o);
}

TEST(SceneRenderer, ReadNoiseAddsInQuadrature) {
  SceneOptions o;
  o.show_target = false;
  o.vignetting = 0;
  o.background_reflectance = 0.2;
  o.read_noise_electrons = 300;  // 3.8 DN, twice the shot noise
  expect_noise_matches_model(o);
}

// The physical sensor (SensorExposure, dark current, PRNU, DSNU) on a uniform
// scene: e = scale * signal + dark current * t electrons; temporal variance
// (e + read^2) electrons^2; fixed pattern (prnu * scale * signal)^2 + dsnu^2;
// both times (DN per electron * gain)^2, plus 1/12 DN^2 of rounding. Bounds
// as expect_noise_matches_model: 5.5 standard errors of the sample mean and
// variance over the frame's 420k pixels, from fixed seeds.
struct SensorCase {
  SceneOptions options;
  SensorExposure exposure;
};

SceneOptions flat_scene(double reflectance) {
  SceneOptions o;
  o.show_target = false;
  o.vignetting = 0;
  o.background_reflectance = reflectance;
  return o;
}

void expect_sensor_model(const SensorCase& c, uint64_t seed = 99) {
  const SceneOptions& o = c.options;
  const SceneRenderer r(vision::Camera::paper_default(), vision::Target::paper_default(),
                        codebook(), o);
  cv::Mat f;
  r.render(vision::Pose(), seed, c.exposure).image.convertTo(f, CV_64F);
  cv::Scalar mean, stddev;
  cv::meanStdDev(f, mean, stddev);
  const double n = static_cast<double>(f.total());
  const double dn_per_e = 255 / o.full_well_electrons * c.exposure.gain;
  const double signal_e =
      c.exposure.signal_scale * dn_of(o.background_reflectance, o) * o.full_well_electrons / 255;
  const double e = signal_e + o.dark_current_e_per_s * c.exposure.exposure_time_s;
  const double temporal = o.noise ? e + o.read_noise_electrons * o.read_noise_electrons : 0;
  const double fixed = std::pow(o.prnu_rel * signal_e, 2) + std::pow(o.dsnu_electrons, 2);
  const double var = (temporal + fixed) * dn_per_e * dn_per_e + 1.0 / 12;
  EXPECT_NEAR(mean[0], e * dn_per_e, 5.5 * std::sqrt(var / n));
  EXPECT_NEAR(stddev[0] * stddev[0], var, 5.5 * var * std::sqrt(2 / n));
}

// Photon transfer: the exposure scales the electrons, so the mean and the
// shot-noise variance grow together (variance - read^2 proportional to the
// signal), as on a real sensor (EMVA 1288), not as an image scaled after the noise.
TEST(SceneRenderer, ExposureMovesShotNoiseAlongThePhotonTransferCurve) {
  for (const double scale : {0.5, 2.0}) {
    SCOPED_TRACE(scale);
    expect_sensor_model({flat_scene(0.4), {scale, 0.01, 1}});
  }
}

// Gain acts after the well: at half the exposure and twice the gain the mean
// is that of unity gain, the variance 4 x (e / 2 + read^2) instead of e + read^2.
TEST(SceneRenderer, GainAmplifiesSignalAndNoiseAlike) {
  expect_sensor_model({flat_scene(0.4), {0.5, 0.01, 2.0}});
}

// Dark current: its mean and its shot noise grow with the exposure time.
TEST(SceneRenderer, DarkCurrentGrowsWithExposureTime) {
  SceneOptions o = flat_scene(0.0);
  o.dark_current_e_per_s = 2e5;  // 2000 e- (25.5 DN) in 10 ms
  for (const double t : {0.01, 0.02}) {
    SCOPED_TRACE(t);
    expect_sensor_model({o, {1.0, t, 1}});
  }
}

// PRNU and DSNU are the camera's own fixed pattern: the same in every frame
// (noise off: two render seeds give the same image), with the stated spatial
// spread, another pattern for another fixed_pattern_seed; with noise on, the
// difference of two frames holds the temporal noise only (2 x (e + read^2)).
TEST(SceneRenderer, PrnuAndDsnuAreFixedAcrossFrames) {
  SceneOptions o = flat_scene(0.7);
  o.noise = false;
  o.prnu_rel = 0.02;
  o.dsnu_electrons = 30;
  expect_sensor_model({o, {1.0, 0.01, 1}}, 1);
  const SceneRenderer r(vision::Camera::paper_default(), vision::Target::paper_default(),
                        codebook(), o);
  EXPECT_EQ(
      cv::countNonZero(r.render(vision::Pose(), 1).image != r.render(vision::Pose(), 2).image), 0);
  SceneOptions other = o;
  other.fixed_pattern_seed = 2;
  const SceneRenderer r2(vision::Camera::paper_default(), vision::Target::paper_default(),
                         codebook(), other);
  EXPECT_GT(
      cv::countNonZero(r.render(vision::Pose(), 1).image != r2.render(vision::Pose(), 1).image),
      100000);

  o.noise = true;
  const SceneRenderer noisy(vision::Camera::paper_default(), vision::Target::paper_default(),
                            codebook(), o);
  cv::Mat a, b;
  noisy.render(vision::Pose(), 5, {1.0, 0.01, 1}).image.convertTo(a, CV_64F);
  noisy.render(vision::Pose(), 6, {1.0, 0.01, 1}).image.convertTo(b, CV_64F);
  cv::Scalar mean, stddev;
  cv::meanStdDev(a - b, mean, stddev);
  const double e = dn_of(o.background_reflectance, o) * o.full_well_electrons / 255;
  const double dn_per_e = 255 / o.full_well_electrons;
  const double var =
      2 * ((e + o.read_noise_electrons * o.read_noise_electrons) * dn_per_e * dn_per_e + 1.0 / 12);
  const double n = static_cast<double>(a.total());
  EXPECT_NEAR(stddev[0] * stddev[0], var, 5.5 * var * std::sqrt(2 / n));
}

// The well saturates before the gain: 3x the electrons of a 0.7 scene
// overflow the full well, and at gain 0.4 every pixel reads exactly
// 255 DN x 0.4 = 102 DN, whatever the noise draws.
TEST(SceneRenderer, WellSaturatesBeforeTheGain) {
  const SceneRenderer r(vision::Camera::paper_default(), vision::Target::paper_default(),
                        codebook(), flat_scene(0.7));
  const cv::Mat image = r.render(vision::Pose(), 3, {3.0, 0.01, 0.4}).image;
  EXPECT_EQ(cv::countNonZero(image != 102), 0);
}

// Thin-lens defocus: blur circle c = f^2 / (N (s_f - f)) |s - s_f| / s,
// sigma = c / 4 / pitch. By hand for the paper camera (fx 706.1 px, 8.6 um
// cells: f = 6.0725 mm) at f/4 focused at 0.4 m: at 0.1 m c = 70.21 um =
// 8.164 px, sigma 2.041 px; zero at the focus distance. The renderer blurs
// with exactly hypot(blur_sigma_px, defocus): the same image as an in-focus
// render with that PSF (noise off, bit for bit).
TEST(SceneRenderer, DefocusFollowsTheThinLensBlurCircle) {
  SceneOptions o;
  o.noise = false;
  o.f_number = 4;
  o.focus_distance_m = 0.4;
  o.pixel_pitch_m = 8.6e-6;
  const double fx = vision::Camera::paper_default().intrinsics().fx;
  EXPECT_NEAR(defocus_sigma_px(o, fx, 0.1), 2.041, 1e-3);
  EXPECT_EQ(defocus_sigma_px(o, fx, 0.4), 0.0);
  EXPECT_GT(defocus_sigma_px(o, fx, 0.15), defocus_sigma_px(o, fx, 0.3));
  EXPECT_GT(defocus_sigma_px(o, fx, 1.0), defocus_sigma_px(o, fx, 0.6));
  const vision::Pose T = pose(0.2, 10, 5, 0);
  SceneOptions in_focus = o;
  in_focus.f_number = 0;
  in_focus.blur_sigma_px = std::hypot(o.blur_sigma_px, defocus_sigma_px(o, fx, 0.2));
  const SceneRenderer defocused(vision::Camera::paper_default(), vision::Target::paper_default(),
                                codebook(), o);
  const SceneRenderer reference(vision::Camera::paper_default(), vision::Target::paper_default(),
                                codebook(), in_focus);
  EXPECT_EQ(cv::countNonZero(defocused.render(T, 1).image != reference.render(T, 1).image), 0);
}

// Vignetting: gain 1 - v (r / r_corner)^2, so the farthest image corner
// receives (1 - v) of the centre's irradiance (noise-free, no blur: exact to
// float rounding, 1e-4 DN).
TEST(SceneRenderer, VignettingDarkensTheFarthestCornerByItsFactor) {
  SceneOptions o = geometry_only();
  o.show_target = false;
  o.vignetting = 0.25;
  const SceneRenderer r(vision::Camera::paper_default(), vision::Target::paper_default(),
                        codebook(), o);
  const cv::Mat irr = r.render_irradiance(vision::Pose(), 1);
  const auto& k = r.camera().intrinsics();
  const double flat = dn_of(o.background_reflectance, o);
  // The principal point (388.0, 269.6) is nearest pixel (388, 270): r = 0.4 px.
  EXPECT_NEAR(irr.at<float>(270, 388), flat, flat * 0.25 * 1e-5);
  // The farthest corner from (388.0, 269.6) is the bottom-left (0, 570).
  ASSERT_GT(std::hypot(k.cx, 570 - k.cy), std::hypot(735 - k.cx, 570 - k.cy));
  EXPECT_NEAR(irr.at<float>(570, 0), flat * 0.75, 1e-3);
}

// Lighting: the sheet's irradiance is 1 + g (p . dir); two blank points of the
// sheet differ by exactly that ratio (no vignetting, noise or blur).
TEST(SceneRenderer, LightingGradientScalesThePaperAlongItsDirection) {
  SceneOptions o = geometry_only();
  o.lighting_gradient_per_m = 0.8;
  o.lighting_direction_deg = 0;  // along +x of the target
  const SceneRenderer r(vision::Camera::paper_default(), vision::Target::paper_default(),
                        codebook(), o);
  const vision::Pose T = pose(0.5, 0, 0, 0);
  const cv::Mat irr = r.render_irradiance(T, 1);
  // Blank paper left and right of marker 0, clear of every quiet zone.
  const Eigen::Vector2d a = r.camera().project(T * Eigen::Vector3d(-0.07, 0.0, 0));
  const Eigen::Vector2d b = r.camera().project(T * Eigen::Vector3d(0.07, 0.0, 0));
  const double ia =
      irr.at<float>(static_cast<int>(std::lround(a.y())), static_cast<int>(std::lround(a.x())));
  const double ib =
      irr.at<float>(static_cast<int>(std::lround(b.y())), static_cast<int>(std::lround(b.x())));
  // Rounding a point to its pixel moves it by <= 0.5 px = 0.35 mm at 0.5 m:
  // a ratio error of 0.8 * 0.00035 = 3e-4.
  EXPECT_NEAR(ib / ia, (1 + 0.8 * 0.07) / (1 - 0.8 * 0.07), 1e-3);
}

// A 4-bit ADC leaves only multiples of 16 DN.
TEST(SceneRenderer, CoarseAdcQuantizesToItsLevels) {
  SceneOptions o;
  o.adc_bits = 4;
  const SceneRenderer r(vision::Camera::paper_default(), vision::Target::paper_default(),
                        codebook(), o);
  const cv::Mat image = r.render(pose(0.4, 10, 0, 0), 2).image;
  int off_level = 0, levels = 0;
  std::vector<bool> seen(256, false);
  for (int v = 0; v < image.rows; ++v) {
    for (int u = 0; u < image.cols; ++u) {
      const int value = image.at<uint8_t>(v, u);
      off_level += value % 16 != 0 ? 1 : 0;
      if (!seen[value]) ++levels;
      seen[value] = true;
    }
  }
  EXPECT_EQ(off_level, 0);
  EXPECT_GT(levels, 5);
}

// A 12-bit ADC digitizes the same electrons and noise draws in 16 times
// finer steps: 0 .. 4095 in CV_16UC1. Rescaled to 8 bits it is the 8-bit
// render of the same seed within 1 DN (two roundings of the same signal:
// round(round(16.06 dn) / 16.06) is within 0.5 + 0.03 DN of dn, the 8-bit
// code within 0.5), and it takes more than 256 distinct values.
TEST(SceneRenderer, TwelveBitAdcIsTheSameSignalInFinerSteps) {
  SceneOptions o8, o12;
  o12.adc_bits = 12;
  const SceneRenderer r8(vision::Camera::paper_default(), vision::Target::paper_default(),
                         codebook(), o8);
  const SceneRenderer r12(vision::Camera::paper_default(), vision::Target::paper_default(),
                          codebook(), o12);
  const cv::Mat a = r8.render(pose(0.4, 10, 0, 0), 3).image;
  const cv::Mat b = r12.render(pose(0.4, 10, 0, 0), 3).image;
  ASSERT_EQ(a.type(), CV_8UC1);
  ASSERT_EQ(b.type(), CV_16UC1);
  cv::Mat b8;
  b.convertTo(b8, CV_8U, 255.0 / 4095.0);
  EXPECT_LE(cv::norm(a, b8, cv::NORM_INF), 1);
  std::vector<bool> seen(4096, false);
  int levels = 0;
  for (int v = 0; v < b.rows; ++v)
    for (int u = 0; u < b.cols; ++u) {
      const int value = b.at<uint16_t>(v, u);
      ASSERT_LE(value, 4095);
      if (!seen[static_cast<size_t>(value)]) ++levels;
      seen[static_cast<size_t>(value)] = true;
    }
  EXPECT_GT(levels, 256);
}

TEST(SceneRenderer, SameSeedGivesTheSameFrameAndAnotherSeedOtherNoise) {
  const SceneRenderer r(vision::Camera::paper_default(), vision::Target::paper_default(),
                        codebook());
  const vision::Pose T = pose(0.5, 10, 5, 0);
  const RenderedFrame a = r.render(T, 5), b = r.render(T, 5), c = r.render(T, 6);
  EXPECT_EQ(cv::norm(a.image, b.image, cv::NORM_INF), 0);
  EXPECT_GT(cv::norm(a.image, c.image, cv::NORM_INF), 0);
}

TEST(SceneRenderer, MarkerCutByTheImageBorderIsNotFullyVisible) {
  const SceneRenderer& r = geometry_renderer();
  // Marker 0 at 0.15 m, shifted 8 cm left: its left part leaves the image.
  const RenderedFrame frame = r.render(pose(0.15, 0, 0, 0, {-0.08, 0}), 1);
  ASSERT_FALSE(frame.markers.empty());
  const MarkerTruth& m0 = frame.markers[0];
  EXPECT_EQ(m0.id, 0);
  EXPECT_FALSE(m0.fully_visible);
  EXPECT_LT(m0.border_distance_px, 0);
  EXPECT_LT(m0.corners_px[0].x(), 0);
  // The whole sheet at 0.8 m: every marker inside with room to spare.
  for (const MarkerTruth& m : r.render(pose(0.8, 0, 0, 0), 1).markers) {
    EXPECT_TRUE(m.fully_visible) << m.id;
    EXPECT_GT(m.border_distance_px, 50) << m.id;
  }
}

// An occluder is flagged exactly on the markers whose pixels it changes (or
// comes within the blur's reach of, 3 sigma + 1 px; here sigma = 0).
TEST(SceneRenderer, OccludedMarkersAreFlaggedWhereTheOccluderChangesThem) {
  SceneOptions o = geometry_only();
  o.occluders = 2;
  const SceneRenderer with(vision::Camera::paper_default(), vision::Target::paper_default(),
                           codebook(), o);
  const SceneRenderer& without = geometry_renderer();
  int flagged = 0;
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    const vision::Pose T = pose(0.7, 15, -10, 5);
    const RenderedFrame a = with.render(T, seed);
    const cv::Mat diff =
        cv::abs(with.render_irradiance(T, seed) - without.render_irradiance(T, seed));
    for (const MarkerTruth& m : a.markers) {
      cv::Mat mask(diff.size(), CV_8UC1, cv::Scalar(0));
      std::vector<cv::Point> quad;
      for (const auto& c : m.corners_px) {
        quad.emplace_back(static_cast<int>(std::lround(c.x())),
                          static_cast<int>(std::lround(c.y())));
      }
      cv::fillConvexPoly(mask, quad, cv::Scalar(255));
      // Grow by the flag's margin (1 px) and the rounding of the corners.
      cv::dilate(mask, mask, cv::Mat(), cv::Point(-1, -1), 1);
      double changed = 0;
      cv::minMaxLoc(diff, nullptr, &changed, nullptr, nullptr, mask);
      if (changed > 1e-3) {
        EXPECT_TRUE(m.occluded) << "seed " << seed << " marker " << m.id;
      }
      cv::erode(mask, mask, cv::Mat(), cv::Point(-1, -1), 4);
      cv::minMaxLoc(diff, nullptr, &changed, nullptr, nullptr, mask);
      if (m.occluded && changed <= 1e-3) {
        // Flagged only through the margin: the occluder must be near the outline.
        cv::Mat grown;
        cv::dilate(mask, grown, cv::Mat(), cv::Point(-1, -1), 8);
        cv::minMaxLoc(diff, nullptr, &changed, nullptr, nullptr, grown);
        EXPECT_GT(changed, 1e-3) << "seed " << seed << " marker " << m.id << " flagged far away";
      }
      EXPECT_EQ(m.fully_visible, !m.occluded && m.border_distance_px >= 0);
      flagged += m.occluded ? 1 : 0;
    }
  }
  // Each occluder is placed across a marker's outline: some are flagged.
  EXPECT_GE(flagged, 6);
}

TEST(SceneRenderer, ClutterOnlyFramesHaveNoMarkers) {
  SceneOptions o;
  o.show_target = false;
  o.clutter_shapes = 40;
  const SceneRenderer r(vision::Camera::paper_default(), vision::Target::paper_default(),
                        codebook(), o);
  const RenderedFrame frame = r.render(pose(0.5, 0, 0, 0), 4);
  EXPECT_TRUE(frame.markers.empty());
  cv::Scalar mean, stddev;
  cv::meanStdDev(frame.image, mean, stddev);
  EXPECT_GT(stddev[0], 10) << "clutter should vary far beyond the noise";
}

TEST(SceneRenderer, SheetSeenFromBehindShowsNoMarkers) {
  const SceneRenderer& r = geometry_renderer();
  vision::Pose T = pose(0.5, 180, 0, 0);
  const RenderedFrame frame = r.render(T, 1);
  EXPECT_TRUE(frame.markers.empty());
  // Blank paper fills the centre.
  const double paper = dn_of(r.options().paper_reflectance, r.options());
  EXPECT_NEAR(frame.image.at<uint8_t>(285, 368), paper, 1.0);
}

// A stationary "moving" frame is the static frame (up to float rounding of the
// sample average); a moving one has its edges smeared, so its steepest
// gradient is lower.
TEST(SceneRenderer, MotionBlurSmearsEdgesAndVanishesWithoutMotion) {
  SceneOptions o = geometry_only();
  const SceneRenderer r(vision::Camera::paper_default(), vision::Target::paper_default(),
                        codebook(), o);
  const vision::Pose a = pose(0.4, 5, 0, 0), b = pose(0.4, 5, 0, 0, {0.01, 0});
  const RenderedFrame still = r.render(a, 1), same = r.render_moving(a, a, 1);
  EXPECT_LE(cv::norm(still.image, same.image, cv::NORM_INF), 1);
  const RenderedFrame moving = r.render_moving(a, b, 1);
  cv::Mat gx_still, gx_moving;
  cv::Sobel(still.image, gx_still, CV_32F, 1, 0);
  cv::Sobel(moving.image, gx_moving, CV_32F, 1, 0);
  double max_still = 0, max_moving = 0;
  cv::minMaxLoc(cv::abs(gx_still), nullptr, &max_still);
  cv::minMaxLoc(cv::abs(gx_moving), nullptr, &max_moving);
  EXPECT_LT(max_moving, 0.5 * max_still);
  // Ground truth of a moving frame: the middle of the exposure.
  const auto mid = r.ground_truth(pose(0.4, 5, 0, 0, {0.005, 0}));
  ASSERT_EQ(mid.size(), moving.markers.size());
  EXPECT_LT((mid[0].corners_px[0] - moving.markers[0].corners_px[0]).norm(), 1e-9);
}

TEST(SceneRenderer, OutOfRangeOptionIsRejectedByName) {
  SceneOptions o;
  o.supersampling = 0;
  try {
    SceneRenderer r(vision::Camera::paper_default(), vision::Target::paper_default(), codebook(),
                    o);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("supersampling"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sim::scene
