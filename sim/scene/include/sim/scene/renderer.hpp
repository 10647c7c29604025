// sim::scene::SceneRenderer: the camera image of a printed target sheet seen from a
// pose, rendered physically, with the exact ground-truth corners of every marker.
//
// Pipeline (once per camera: the undistorted ray of every pixel and its
// Jacobian, by inverting the Brown-Conrady model of vision::Camera; per frame):
//   1. geometry: each pixel's ray meets the sheet plane z = 0 (a homography of
//      the undistorted normalized point), giving the pixel's footprint on the
//      sheet (its centre and the 2x2 Jacobian d(target)/d(pixel));
//   2. area-correct lookup: the reflectance averaged over the footprint, exactly
//      integrated on the artwork (per marker a summed-area table of its cell
//      grid; the sheet rectangle analytically). Pixels whose footprint straddles
//      an edge are split in supersampling x supersampling sub-pixels, each
//      integrated over a box of the same second moments as its footprint, so
//      there is no aliasing near (0.1 m, cells of ~60 px) nor far (1 m, cells
//      of ~6 px);
//   3. lighting gradient across the sheet, background (optionally clutter)
//      where the sheet is not, occluders in front;
//   4. optical blur (Gaussian PSF), vignetting;
//   5. sensor: electrons = exposure * full_well * irradiance, shot noise
//      (Poisson, as a Gaussian of variance = electrons) + read noise, gain to
//      8-bit DN, rounding and clipping.
// The artwork is the marker cells and the sheet; the small id/size text that
// vision::artwork prints in the margins is not rendered (it lies in the quiet
// zone's outer part and carries no geometry).
//
// Ground truth: vision::Camera::project of the target's corners (A, B, C, D
// of vision::Target::corners_m), i.e. distorted pixels in OpenCV's convention
// (the centre of the top-left pixel is (0, 0)). The renderer places edges with
// the same model, so a perfect detector finds these corners.
//
// Thread safety: render() and render_moving() are const and may run
// concurrently on one SceneRenderer. The optical blur is cv::GaussianBlur,
// which uses OpenCV's thread pool (cv::setNumThreads(1) for one core).
//
// Cost: building the ray table takes ~50 ms per camera; a 736x571 frame
// takes 4-7 ms on one core (tests/bench/bench_renderer.cpp), render_moving()
// about motion_blur_samples times the geometry part of that.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "vision/camera.hpp"
#include "vision/codebook.hpp"
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
  // Relative irradiance loss at the image corners (natural vignetting, ~cos^4):
  // gain(r) = 1 - vignetting * (r / r_corner)^2, r from the principal point.
  double vignetting = 0.25;

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
  // Bits of the analog-to-digital converter (1 .. 8). The image is always
  // CV_8UC1 (0 .. 255 = 0 .. full well); fewer bits quantize it more coarsely.
  int adc_bits = 8;
  // false: no shot or read noise (deterministic, for geometry tests).
  bool noise = true;

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
  cv::Mat image;  // CV_8UC1, camera.width_px() x camera.height_px()
  // One entry per marker of the target whose centre is in front of the camera,
  // in the target's marker order; empty when show_target is false or when the
  // camera sees the back of the sheet (then drawn blank).
  std::vector<MarkerTruth> markers;
};

class SceneRenderer {
 public:
  // Precomputes the per-pixel rays of the camera (once). Throws
  // std::invalid_argument if a target marker's id is not in the codebook or an
  // option is out of range (naming it).
  SceneRenderer(const vision::Camera& camera, const vision::Target& target,
                const vision::Codebook& codebook, SceneOptions options = {});
  ~SceneRenderer();
  SceneRenderer(SceneRenderer&&) noexcept;
  SceneRenderer& operator=(SceneRenderer&&) noexcept;

  // One frame from a static pose. The same pose and seed give the same image.
  RenderedFrame render(const vision::Pose& T_cam_target, uint64_t seed) const;

  // One frame during which the target moves from T_cam_target_start to
  // T_cam_target_end (rotation by slerp, translation linear), exposure spread
  // over options.motion_blur_samples poses. Ground truth at the middle pose.
  RenderedFrame render_moving(const vision::Pose& T_cam_target_start,
                              const vision::Pose& T_cam_target_end, uint64_t seed) const;

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
