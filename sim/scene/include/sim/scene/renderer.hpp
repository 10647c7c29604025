// sim::scene::SceneRenderer: the camera image of a printed target sheet seen from a
// pose, rendered physically, with the exact ground-truth corners of every marker.
//
// Pipeline (once per camera: the undistorted ray of every pixel and its
// Jacobian, by inverting the Brown-Conrady model of vision::Camera; per frame):
//   1. geometry: each pixel's ray meets the sheet plane z = 0 (a homography of
//      the undistorted normalized point), or the bowed sheet a few steps from
//      it (SceneOptions::bow_sag_m), giving the pixel's footprint on the
//      sheet (its centre and the 2x2 Jacobian d(target)/d(pixel));
//   2. area-correct lookup: the reflectance averaged over the footprint, exactly
//      integrated on the artwork (per marker a summed-area table of its cell
//      grid; the sheet rectangle analytically). Pixels whose footprint straddles
//      an edge are split in supersampling x supersampling sub-pixels, each
//      integrated over a box of the same second moments as its footprint, so
//      there is no aliasing near (0.1 m, cells of ~60 px) nor far (1 m, cells
//      of ~6 px);
//   3. lighting gradient across the sheet, the glare lobe of a lamp mirrored
//      in it (weighted by the paper's and the toner's gloss), background
//      (optionally clutter) where the sheet is not, occluders in front;
//   4. optical blur (Gaussian PSF), vignetting;
//   5. sensor: electrons = signal_scale * flicker * exposure * full_well
//      * irradiance * (1 + PRNU), plus the dark signal (dark current x exposure time +
//      DSNU); shot noise (Poisson, as a Gaussian of variance = electrons) +
//      read noise; the well clips at full_well; gain to 8-bit DN, rounding
//      and clipping.
// The artwork is the marker cells and the sheet; the small id/size text that
// vision::artwork prints in the margins is not rendered (it lies in the quiet
// zone's outer part and carries no geometry).
//
// Ground truth: vision::Camera::project (plus SceneOptions::thin_prism) of the target's corners (A,
// B, C, D of vision::Target::corners_m, raised by the sheet's bow, SceneOptions::bow_sag_m), i.e.
// distorted pixels in OpenCV's convention (the centre of the top-left pixel is (0, 0)). The
// renderer places edges with the same model, so a perfect detector finds these corners.
//
// Thread safety: render() and render_moving() are const and may run
// concurrently on one SceneRenderer. The optical blur is cv::GaussianBlur,
// which uses OpenCV's thread pool (cv::setNumThreads(1) for one core).
//
// Cost: building the ray table takes ~50 ms per camera; a 736x571 frame
// takes 4-7 ms on one core (tests/bench/bench_renderer.cpp), render_moving()
// about motion_blur_samples times the geometry part of that. The costliest
// realism (config/realism/paper.toml: defocus, fixed pattern, the physical
// sensor path) measured 1.25-1.4x the default options' time per frame.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "vision/camera.hpp"
#include "vision/codebook.hpp"
#include "vision/marker_family.hpp"
#include "vision/pose.hpp"
#include "vision/target.hpp"

namespace sim::scene {

// Every field's default is the "realistic" setting: a well-lit lab, a
// machine-vision CCD like the paper's Sony XC-555, slight defocus. Clutter,
// occlusion and motion blur are off by default (turn them on per test).
struct SceneOptions {
  // --- artwork sampling ---
  // Sub-pixels per axis in pixels whose footprint straddles an edge (pixels in
  // a uniform region take their exact value directly). Each sub-pixel is an
  // exact integral over a box with its footprint's second moments; the box
  // only approximates a rotated/sheared footprint, so edges move slightly.
  // Measured worst edge placement (tests/sim, 0.12-0.30 m, tilt up to 40
  // degrees): 1 -> 0.010 px, 2 -> 0.004 px, 4 -> 0.001 px. Cost grows with
  // the square, for edge pixels only (4: 4-7 ms per frame in total).
  int supersampling = 4;

  // --- scene reflectances (0 black .. 1 perfect white) ---
  double paper_reflectance = 0.85;       // white paper and the white cells
  double ink_reflectance = 0.05;         // black laser toner
  double background_reflectance = 0.30;  // what surrounds the sheet (mean when cluttered)
  // Show the sheet at all. false renders background (and clutter) only, e.g.
  // for false-detection tests.
  bool show_target = true;

  // --- illumination ---
  // Relative change of the illumination per metre across the sheet, along
  // lighting_direction_deg (0 = +x of the target, 90 = +y):
  // illumination(p) = 1 + lighting_gradient_per_m * (p . dir), clamped >= 0.05.
  // 0.5 /m is a +-5 % change over an A4 sheet; larger values stress the
  // detector's thresholds (a white cell on one side may be darker than the
  // black border's neighbourhood on the other).
  double lighting_gradient_per_m = 0.5;
  double lighting_direction_deg = 30.0;

  // --- optics ---
  // Standard deviation of the Gaussian point-spread function, pixels (defocus,
  // lens aberrations, the sensor's pixel crosstalk). 0 = no blur. Larger
  // values smooth edges (fewer detections of small markers, corners still
  // unbiased because the PSF is symmetric).
  double blur_sigma_px = 0.6;
  // Thin-lens defocus, added in quadrature to blur_sigma_px (0 = off, the
  // default). The lens is focused at focus_distance_m with f-number f_number;
  // its focal length is fx * pixel_pitch_m (the camera's own fx). An object
  // at depth s (the target origin's z in the camera frame, one value per
  // frame: the depth change across a tilted sheet is ignored) is imaged as a
  // blur circle of diameter c = f^2 / (N (s_f - f)) |s - s_f| / s on the
  // sensor, c / pitch pixels, whose per-axis standard deviation as a uniform
  // disk is c / 4: the Gaussian sigma used (defocus_sigma_px).
  double f_number = 0;
  double focus_distance_m = 0.4;
  double pixel_pitch_m = 8.6e-6;  // the XC-555's 8.6 um cells
  // Relative irradiance loss at the image corners (natural vignetting, ~cos^4):
  // gain(r) = 1 - vignetting * (r / r_corner)^2, r from the principal point.
  double vignetting = 0.25;
  // Thin-prism lens terms s1..s4 of the true lens (OpenCV's order, Weng et
  // al. 1992): xd += s1 r2 + s2 r2^2, yd += s3 r2 + s4 r2^2 on top of the
  // camera's own model, r2 on the normalized image plane; a decentred or
  // tilted lens element gives |s| ~ 1e-4 .. 1e-3. vision::Camera holds them
  // too, so a calibration can fit them (rig calibrate --distortion).
  // Rendering and ground truth (MarkerTruth::corners_px) both use them.
  // All 0 (default): the camera's own model exactly.
  std::array<double, 4> thin_prism{};
  // The radial term of the next order, r^8 (Brown, "Close-range camera
  // calibration", Photogrammetric Engineering 37(8), 1971: the radial series
  // k1 r^2 + k2 r^4 + k3 r^6 + k4 r^8 + ..., which calibrations truncate
  // after k3): x_d += x k4 r2^4, y_d += y k4 r2^4. No model vision::Camera
  // holds has it (OpenCV's k4 is the rational model's), so no calibration
  // fits the true lens exactly. 0 (default): none.
  double radial_k4 = 0;

  // --- sensor ---
  // Fraction of the full well that a perfect white (reflectance 1) at full
  // illumination fills at the image centre. 0.9 puts the paper at ~195 DN.
  double exposure = 0.9;
  // Full-well capacity, electrons: sets the shot noise (a signal of N
  // electrons has a standard deviation of sqrt(N)). 20000 e- gives ~1.5 DN of
  // noise on white paper. Smaller = noisier.
  double full_well_electrons = 20000.0;
  // Read (plus dark and ADC) noise, electrons RMS, added in quadrature.
  double read_noise_electrons = 20.0;
  // Bits of the analog-to-digital converter (1 .. 16). Up to 8 the image is
  // CV_8UC1 (0 .. 255 = 0 .. full well); fewer bits quantize it more coarsely.
  // Above 8 it is CV_16UC1, 0 .. 2^adc_bits - 1 = 0 .. full well (a 12-bit
  // sensor: 0 .. 4095), the same electrons and noise in finer steps.
  int adc_bits = 8;
  // false: no shot or read noise (deterministic, for geometry tests).
  bool noise = true;
  // Exposure time (seconds) of render() and render_moving() without
  // SensorExposure: the time at which `exposure` holds. Sets the dark signal.
  double exposure_time_s = 0.01;
  // Dark current, electrons per second per pixel (mean; its shot noise is
  // added with the signal's). A cooled CCD ~0.1 e-/s, a warm CMOS 1-50 e-/s.
  double dark_current_e_per_s = 0;
  // Photo-response non-uniformity: relative 1-sigma of each pixel's gain,
  // fixed over frames (EMVA 1288 PRNU; 0.5-1 % typical). 0 = uniform.
  double prnu_rel = 0;
  // Dark-signal non-uniformity: 1-sigma of each pixel's fixed dark offset,
  // electrons (EMVA 1288 DSNU; a few e- typical). 0 = none.
  double dsnu_electrons = 0;
  // Seed of the PRNU/DSNU pattern: one pattern per camera, the same in every
  // frame (unlike the render seed, which draws the temporal noise).
  uint64_t fixed_pattern_seed = 1;

  // --- specular glare (off by default: glare_peak 0) ---
  // A lamp far from the sheet, seen mirrored in it: the sheet reflects it in a
  // lobe about the mirror direction (Phong-like, the roughness of paper and
  // toner). With the lamp at glare_light_tilt_deg from the sheet's normal,
  // towards glare_light_azimuth_deg on the sheet (0 = target +x, 90 = +y),
  // its mirror direction R is fixed in the target frame; the spot lies where
  // the direction from the sheet to the camera is R, so it moves over the
  // sheet with the camera's position and over the image with its rotation (a
  // pixel whose ray d sees the sheet shows the lobe at the angle between d and
  // -R, seen from any point). Added radiance, in reflectance units (1 = a
  // perfect white diffuser at full illumination):
  //   glare_peak * gloss * exp(-(1 - cos angle) / sigma^2),  sigma = glare_lobe_deg,
  // a Gaussian of sigma glare_lobe_deg in the angle for small angles, so the
  // spot's image radius is ~fx * sigma pixels at any distance. gloss is
  // paper_gloss on paper, ink_gloss on toner. Where paper + glare exceeds
  // 1 / exposure the well saturates. The bow of the sheet does not tilt the
  // lobe (its slope, < 1 degree, is far below a lobe of several degrees).
  double glare_peak = 0;
  double glare_lobe_deg = 8;
  double glare_light_tilt_deg = 20;
  double glare_light_azimuth_deg = 0;
  // Specular reflectance of the paper and of the toner relative to the
  // reference of glare_peak (1 = plain office paper). Fused laser toner is a
  // polymer film, glossier than paper: ~2-4. Only with glare_peak > 0.
  double paper_gloss = 1;
  double ink_gloss = 1;

  // --- lamp flicker (off by default: flicker_modulation 0) ---
  // The lamps' intensity I(t) = I0 (1 + m sin(2 pi f t + phase)), f twice the
  // mains frequency (100 Hz on 50 Hz mains, 120 Hz on 60 Hz). An exposure of T
  // seconds from t0 collects the mean over [t0, t0 + T]:
  //   I0 (1 + m sinc(pi f T) sin(2 pi f (t0 + T / 2) + phase)),  sinc x = sin x / x,
  // so frames taken at different times differ by a relative amplitude of
  // m |sinc(pi f T)|: m for T << 1 / f, 0 when T covers whole periods, and
  // falling as 1 / (pi f T) between. Applied to the whole scene (sheet,
  // glare and background) in the sensor stage, from SensorExposure's
  // start_time_s and exposure_time_s (flicker_gain below).
  double flicker_modulation = 0;  // m, 0 .. 1 (percent flicker / 100, IEEE 1789)
  double flicker_frequency_hz = 100;
  double flicker_phase_deg = 0;

  // --- bow of the sheet (off by default: bow_sag_m 0) ---
  // The sheet is not flat: it bulges towards the camera by
  //   h(X, Y) = bow_sag_m * (1 - wx u^2 - wy v^2),
  // u, v = the position across the sheet scaled to -1 .. 1 (sheet centre 0,
  // edges +-1), i.e. a paraboloid whose rim lies on the plane z = 0 of the
  // target frame: kDome wx = wy = 1/2 (the corners on the plane, the centre
  // raised by the sag), kCylinderX wx = 1, wy = 0 (curled along the sheet's x:
  // the left and right edges on the plane), kCylinderY wx = 0, wy = 1. A
  // point of the artwork at (X, Y) is rendered, and its truth projected, at
  // (X, Y, -h(X, Y)) in the target frame (z points into the sheet), so a
  // marker at sag h is h closer to the camera. The artwork is placed by its
  // projection on the plane: the arc length's excess (~(2 h / W)^2, < 1e-4 for
  // a 1 mm sag over A4) is not modelled.
  enum class BowShape { kDome, kCylinderX, kCylinderY };
  double bow_sag_m = 0;
  BowShape bow_shape = BowShape::kDome;

  // --- optional disturbances (off by default) ---
  // Random shapes (rectangles, quadrilaterals, ellipses, lines, checker
  // patches, grey levels 0.05 .. 0.95) on the background behind the sheet,
  // drawn from the render seed; clutter_shapes shapes per frame. More shapes = more detector
  // candidates (false-detection tests), slower render.
  int clutter_shapes = 0;
  // Opaque occluders (a cable, a finger: a rotated bar of flat grey 0.1-0.6)
  // in front of the sheet, each placed across the outline of a randomly
  // chosen marker so that it cuts it; widths drawn in
  // [occluder_min_width_px, occluder_max_width_px]. They are fixed in the
  // image (they do not move in render_moving()).
  int occluders = 0;
  double occluder_min_width_px = 8.0;
  double occluder_max_width_px = 40.0;
  // Poses sampled uniformly in time between the start and the end pose by
  // render_moving() (irradiance averaged over the exposure). More samples =
  // smoother blur, proportionally slower. render() ignores it.
  int motion_blur_samples = 8;
};

// How a frame is exposed, relative to SceneOptions: the camera's exposure
// time and gain act on the sensor physically (before the shot noise for the
// signal, after it for the gain), not on the finished image.
struct SensorExposure {
  // Signal electrons relative to SceneOptions::exposure (the exposure time
  // over the nominal one): 2 = twice the photons, so sqrt(2) the shot noise.
  double signal_scale = 1;
  // Exposure time, seconds: the dark signal is dark_current_e_per_s times it.
  double exposure_time_s = 0.01;
  // Analogue gain, linear (DN per DN at unity gain): scales signal and noise
  // alike, after the well; the ADC clips at its top level.
  double gain = 1;
  // When the exposure starts, seconds on the scene's clock (the lamps' phase
  // is SceneOptions::flicker_phase_deg at 0): sets the flicker of the frame.
  double start_time_s = 0;
};

// The relative illumination of an exposure of exposure_time_s seconds that
// starts at start_time_s, under the lamps' flicker of `options` (see
// SceneOptions::flicker_modulation): 1 + m sinc(pi f T) sin(2 pi f (t0 + T/2) + phase);
// exactly 1 when flicker_modulation is 0. exposure_time_s 0 gives the
// instantaneous intensity.
double flicker_gain(const SceneOptions& options, double start_time_s, double exposure_time_s);

// The sag of the sheet of `target` at (X, Y) of the target frame, metres
// towards the camera (see SceneOptions::bow_sag_m); 0 when bow_sag_m is 0.
double sheet_sag_m(const SceneOptions& options, const vision::Target& target, double x_m,
                   double y_m);

struct MarkerTruth {
  int id = 0;
  // Corners A, B, C, D (order of vision::Target::corners_m): distorted pixels,
  // OpenCV convention. For render_moving(): at the middle of the exposure.
  std::array<Eigen::Vector2d, 4> corners_px;
  // The whole black square (its outline, sampled along the distorted edges) is
  // in front of the camera, inside [0, width - 1] x [0, height - 1] and under
  // no occluder (nor within 3 blur sigmas + 1 px of one). A detector must not
  // place corners from a marker that is not fully visible; a fully visible
  // marker whose border_distance_px is only a pixel or two cannot be found
  // either (its outer edge has no white beyond it), so detection-rate tests
  // should ask for a margin.
  bool fully_visible = false;
  bool occluded = false;  // some occluder covers part of the marker
  // Smallest distance from the marker's outline to the image border, pixels
  // (negative when the outline leaves the image).
  double border_distance_px = 0;
};

struct RenderedFrame {
  // camera.width_px() x camera.height_px(): CV_8UC1, or CV_16UC1 when
  // SceneOptions::adc_bits > 8.
  cv::Mat image;
  // One entry per marker of the target whose centre is in front of the camera,
  // in the target's marker order; empty when show_target is false or when the
  // camera sees the back of the sheet (then drawn blank).
  std::vector<MarkerTruth> markers;
};

// The defocus blur of `options` for an object at depth_m (metres, > 0) seen
// by a camera of focal length fx_px pixels: c / 4 in pixels (see
// SceneOptions::f_number); 0 when f_number is 0.
double defocus_sigma_px(const SceneOptions& options, double fx_px, double depth_m);

class SceneRenderer {
 public:
  // Precomputes the per-pixel rays of the camera (once). Throws
  // std::invalid_argument if a target marker's id is not in the codebook or an
  // option is out of range (naming it).
  SceneRenderer(const vision::Camera& camera, const vision::Target& target,
                const vision::Codebook& codebook, SceneOptions options = {});
  // The markers drawn in any family's cells (e.g. MarkerFamily::named(target.family));
  // std::invalid_argument if a marker id is not in the family.
  SceneRenderer(const vision::Camera& camera, const vision::Target& target,
                const vision::MarkerFamily& family, SceneOptions options = {});
  ~SceneRenderer();
  SceneRenderer(SceneRenderer&&) noexcept;
  SceneRenderer& operator=(SceneRenderer&&) noexcept;

  // One frame from a static pose. The same pose and seed give the same image.
  // Without `exposure`: SensorExposure{1, options.exposure_time_s, 1}.
  RenderedFrame render(const vision::Pose& T_cam_target, uint64_t seed) const;
  RenderedFrame render(const vision::Pose& T_cam_target, uint64_t seed,
                       const SensorExposure& exposure) const;

  // One frame during which the target moves from T_cam_target_start to
  // T_cam_target_end (rotation by slerp, translation linear), exposure spread
  // over options.motion_blur_samples poses. Ground truth at the middle pose.
  RenderedFrame render_moving(const vision::Pose& T_cam_target_start,
                              const vision::Pose& T_cam_target_end, uint64_t seed) const;
  RenderedFrame render_moving(const vision::Pose& T_cam_target_start,
                              const vision::Pose& T_cam_target_end, uint64_t seed,
                              const SensorExposure& exposure) const;

  // The noise-free irradiance image before the sensor stage (CV_32FC1, in DN
  // units 0 .. 255 as the sensor would report without noise or quantization):
  // for tests of the noise model and for callers who add their own sensor.
  cv::Mat render_irradiance(const vision::Pose& T_cam_target, uint64_t seed) const;

  // Ground truth only (no image): the markers as render() would report them
  // without occluders.
  std::vector<MarkerTruth> ground_truth(const vision::Pose& T_cam_target) const;

  const vision::Camera& camera() const;
  const vision::Target& target() const;
  const SceneOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::scene
