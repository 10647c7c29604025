// vision::Detector: finds and identifies the coded square fiducials of
// vision::Codebook in a camera image, with sub-pixel corners that follow the
// lens distortion.
//
// Pipeline (Maidi, Didier, Ababsa, Mallem 2010, §3, steps 1-7 and eq. 30):
//  1. Canny edges of the grey image (Gaussian smoothing, Sobel gradient,
//     non-maximum suppression, hysteresis) [Canny 1986];
//  2. Gaussian smoothing of the edge map, joining nearby edge pixels;
//  3. dilation, closing the remaining holes between edge segments;
//  4. contours approximated by polygons with a tolerance proportional to the
//     contour perimeter;
//  5-7. only polygons with four vertices, convex, with every corner angle
//     "near" a right angle, are square candidates. "Near" has to allow for
//     perspective: a square tilted 40 degrees about its diagonal images as a
//     rhombus of 75/105 degrees, and at 0.1 m the near side of a 5 cm square
//     is up to 1.4 times longer than the far one.
//  By default steps 1-7 run on the image halved by cv::pyrDown's 5x5
//  Gaussian (DetectorParameters::candidate_decimation, as AprilTag's
//  quad_decimate). The halving and steps 1-3 give OpenCV's pyrDown, Canny
//  and dilate pixel for pixel, from the detector's own faster loops
//  (detector_half_image.cpp, detector_edge_map.cpp). Steps 1-7 only have to
//  find candidates, which everything below re-measures on the full image.
//  Then, beyond the paper (detector_edges.cpp):
//  8. each side is re-located to sub-pixel precision from the image gradient
//     along it. The side of a printed square is a straight line on the sheet
//     and therefore a straight line in the undistorted normalized image plane,
//     but a curve in the distorted image: edge points are found in the image,
//     moved into the normalized plane through the camera model, fitted there
//     by straight lines, and the lines intersected; the intersections are
//     distorted back to pixels. A side cut by the image border, or one whose
//     edge is missing or bent along part of its length (an occluder), rejects
//     the marker: a corner is never extrapolated from a partial side.
//  9. identification (detector_identify.cpp): the 6x6 cell grid is sampled
//     through the homography of the refined corners (eq. 30), computed in the
//     undistorted plane where it is exact, and each sample point is distorted
//     back to the image; the 20 border cells must be black and the 16 code
//     bits decode in one of four orientations; the corners are then reported
//     in the order A, B, C, D of the target layout (vision/target.hpp).
//
// Pixel convention: OpenCV's, the centre of the top-left pixel is (0, 0).
#pragma once

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <vector>

#include "vision/camera.hpp"
#include "vision/codebook.hpp"

namespace vision {

// Every threshold of the detector, with its effect and what it costs. The
// defaults are set for the paper's camera (736x571, Sony XC-555 lens) and
// 5 cm markers at 0.1-1.0 m with up to 40 degrees of tilt; the detector tests
// (tests/vision/detector_rendered_test.cpp) hold them to their figures.
struct DetectorParameters {
  // ---- Candidates: paper §3 steps 1-7 ---------------------------------------

  // Canny hysteresis thresholds on the 3x3 Sobel gradient magnitude (L1 norm,
  // |gx| + |gy|, about 8 x grey levels per pixel). An edge starts where the
  // gradient exceeds canny_high and continues while it exceeds canny_low. A
  // step of contrast C blurred by sigma px peaks near 3.2 C / sigma, so with
  // the optics' blur and canny_sigma_px together near 1.2 px the defaults find
  // edges of C >= 20 grey levels (printed black on white gives 100-200).
  // Lower: fainter or more blurred markers are found, at the cost of more
  // noise edges, more contours and more time. Higher: faster, fewer clutter
  // candidates, but dim, blurred or far markers are lost.
  double canny_low = 25;
  double canny_high = 50;

  // Standard deviation (pixels) of the Gaussian that smooths the image before
  // the gradient, the first stage of Canny's operator; 0 skips it (OpenCV's
  // cv::Canny alone). Only the candidates come from the smoothed image; the
  // sub-pixel sides and the code are read on the original. Larger suppresses
  // noise edges (fewer broken outlines and spurious contours in noisy images,
  // hence also less time) but merges the edges of small code cells and blunts
  // the corners of distant markers. Used when candidate_decimation is 1.
  double canny_sigma_px = 0.8;

  // 1: the candidate steps 1-7 run on the full image. 2: on the image
  // reduced by cv::pyrDown's kernel (whose 5x5 Gaussian then serves as Canny's
  // smoothing stage instead of canny_sigma_px), like AprilTag's
  // quad_decimate: steps 1-7 take about a third of the time (bench_detector
  // times the whole detector; scripts/perf_table), and the sub-pixel sides and the code are still
  // read on the full image, so the corners do not change. The cost: outlines of markers under ~25
  // px a side merge with their code edges at half resolution and are lost sooner. All sizes here
  // stay in full-resolution pixels (the kernels below are halved, rounded up to odd).
  int candidate_decimation = 2;

  // Side of the Gaussian kernel that smooths the edge map (paper step 2),
  // pixels, odd; 0 or 1 disables it. Smoothing joins edge pixels that Canny
  // left a pixel apart, so a marker's outline closes into one contour. Larger
  // closes wider gaps (blur, noise) but merges the outline with the inner edge
  // of the black border on small markers, and costs time.
  int smoothing_kernel_px = 3;

  // Side of the square structuring element of the dilation (paper step 3),
  // pixels, odd; 0 or 1 disables it. Same trade-off as the smoothing: closes
  // holes between edge segments, but thickens edges, so that outlines of
  // small or distant markers (black border < 2 x this) merge with their code
  // edges. The contours it leaves lie about (smoothing + dilation) / 2 px off
  // the true edge; the sub-pixel stage searches for the edge that far.
  int dilation_kernel_px = 3;

  // Polygon approximation tolerance (paper step 4), as a fraction of the
  // contour perimeter (cv::approxPolyDP epsilon = fraction x perimeter).
  // Larger accepts sides curved by lens distortion and corners rounded by
  // blur, and also shapes that are not quadrilaterals (which the edge fit and
  // the code then reject, at a cost in time). Smaller splits distorted sides
  // into more than four vertices, losing markers near the image border, and
  // at half resolution (candidate_decimation 2) rejects the jagged outlines
  // of small, noisy or blurred markers: 0.04 lost 1 % of them there.
  double approx_epsilon_fraction = 0.05;

  // Accepted contour perimeter, pixels. Markers smaller than min_perimeter_px
  // are not searched for: below about 16 px a side, a code cell is under
  // 2.7 px and cannot be read reliably, and tiny contours are mostly noise.
  // Raise it to save time when markers are known to be large.
  double min_perimeter_px = 56;
  // Upper bound, as a multiple of the image's (width + height): a marker
  // cannot be larger than the image. Lower it to skip large quadrilaterals
  // (sheet edges, frames) early.
  double max_perimeter_image_fraction = 2.0;

  // Shortest accepted side of the approximated polygon, pixels. Rejects
  // slivers (a marker seen edge-on cannot be decoded anyway).
  double min_side_px = 10;

  // Paper step 7: largest accepted |cos| of any corner angle of the polygon.
  // 0 accepts only exact right angles; 0.5 accepts 60-120 degrees. Tilting
  // a square 40 degrees about its diagonal gives |cos| = 0.26; with
  // perspective at 0.1 m and the lens distortion the worst case of the test
  // distribution (20,000 poses, sheet tilted up to 40 degrees from the line
  // of sight to the pose marker) is 0.44 for the pose marker; the sheet's
  // other markers, seen more obliquely from 0.1 m, exceed 0.6 in 0.05 % of
  // their views. Larger accepts stronger tilts and closer markers, at the
  // cost of more candidates from clutter (each costs an edge fit; false
  // detections are still excluded by the code).
  double max_abs_cos_corner = 0.6;

  // ---- Sub-pixel sides ------------------------------------------------------

  // How far (pixels, each way along the normal) the first pass searches for a
  // side's edge around the candidate polygon. It must cover the offset of the
  // dilated contour from the true edge (about 3 px with the defaults) plus
  // the polygon approximation error. Larger tolerates coarser candidates but
  // can jump to a neighbouring edge of the same polarity; smaller is faster.
  double edge_search_px = 5.0;
  // Half-width (pixels) of the window of the later passes, centred on the
  // fitted side. Must exceed the edge's blur (2-3 sigma of optics and pixel)
  // so that the window's ends lie on the plateaus; must stay under one cell
  // of the smallest marker (about 4 px at 1.1 m and 40 degrees), beyond
  // which the code's edges enter the window. 3 px keeps the corners within
  // 0.05 px RMS up to a PSF sigma of 1.5 px.
  double edge_refine_px = 3.0;
  // Number of fit passes: the first from the candidate polygon, each later
  // one re-centred on the sides of the previous. 2 puts the corners within
  // 0.01 px RMS of the 3-pass result at the default blur (0.02 px under a
  // 1.5 px PSF), for 15 % less time; more passes help only heavy blur.
  int edge_passes = 2;

  // Spacing of edge samples along a side, pixels, and the most samples one
  // side gets. More samples average noise better (the corner error falls as
  // 1/sqrt(samples)) and cost time linearly.
  double edge_sample_spacing_px = 1.0;
  int max_edge_samples_per_side = 64;

  // Samples closer than this to a corner (pixels along the side) are not
  // used: the blurred corner of the square rounds the edge there. Larger is
  // safer under heavy blur, smaller keeps more samples on small markers. The
  // exclusion never exceeds 20 % of the side.
  double corner_exclusion_px = 2.5;

  // A sample counts as an edge when its outward dark-to-bright step is at
  // least this fraction of the side's typical (75th percentile) step, and at
  // least min_edge_step grey levels. The relative bound is what detects an
  // occluder: where it covers the side the step vanishes, or shrinks to the
  // step between the black border and a grey occluder. Along one side the
  // step varies by a few percent (lighting gradient, vignetting); higher
  // values catch paler occluders but would start to reject sides that run
  // across a strong lighting change.
  double min_relative_edge_step = 0.75;
  double min_edge_step = 4.0;

  // Occlusion: the fraction of a side's samples that must be edge samples on
  // the fitted line (within max_sample_residual_px), and the longest stretch
  // of the side without one, pixels. An occluder (a cable, a finger) removes
  // the edge over its width (the renderer's narrowest is 8 px), a noise dip
  // over a sample or two. Raise the support or lower the gap to reject markers
  // that are even slightly covered; relax them to keep markers behind thin
  // occluders, at the risk of a corner placed from a partly hidden side.
  double min_edge_support = 0.85;
  double max_edge_gap_px = 3.5;
  // A sample farther than this from its side's fitted line (pixels) is an
  // outlier (noise, an occluder's edge) and is left out of the fit.
  double max_sample_residual_px = 0.6;

  // Largest accepted RMS distance (pixels) of the edge samples from their
  // fitted sides, over the four sides. A printed straight edge fits to well
  // under 0.1 px; a larger residual means a bent or broken outline (a
  // crumpled sheet, a shadow edge, a non-marker). Raise it for poor optics.
  double max_edge_residual_px = 0.35;

  // Margin (pixels) that a side's samples must keep from the image border
  // (their windows are cut there, see min_edge_window_px). Smaller keeps markers closer to the
  // border; below 1 px the edge profile would be read from the replicated border.
  double image_border_margin_px = 1.0;
  // Near the image border a side's profile windows (edge_search_px,
  // edge_refine_px each way) are cut to the part inside the margin, but
  // either side of the edge must keep at least this much (pixels): the
  // window's ends must lie on the black and the white plateaus for the
  // equal-area position to be unbiased, i.e. beyond the edge's blur (~2
  // sigma of a PSF of up to 1 px). A marker whose outline comes nearer the
  // border than image_border_margin_px + this is cut by it.
  double min_edge_window_px = 2.0;

  // A refined corner may move at most this far (pixels) from the candidate
  // polygon's vertex, and at most 30 % of the candidate's shortest side (but
  // always 2 px); farther means the fit locked onto another edge, and the
  // candidate is dropped. Must exceed the contour's offset from the edge
  // (about 3.5 px at a corner with the default kernels) plus the polygon
  // approximation error at a corner (up to a few pixels on small, noisy
  // outlines). Larger keeps more small markers in noisy images; smaller
  // rejects wrong locks earlier (the code and quiet-zone checks reject them
  // later anyway).
  double max_corner_shift_px = 8.0;

  // A marker printed alone on a sheet cut this many cells outside it (`rig
  // marker`'s quiet zone) has the sheet's edge so close to its own that the
  // dilated edges merge and the outline found is the sheet's. When a
  // candidate's sides fail, the marker is looked for in the candidate's inner
  // 6 / (6 + 2 x this) part. 0 disables the retry (a little faster on
  // cluttered images, whose failed candidates are all retried); the retry
  // cannot create a false detection the code checks would not reject anyway.
  int sheet_edge_quiet_cells = 1;

  // ---- Identification (eq. 30) ---------------------------------------------

  // Fraction of a cell's side, centred, over which the cell is averaged (3x3
  // sample points). Larger averages more noise; smaller keeps away from the
  // blurred cell boundaries of small markers.
  double cell_sample_fraction = 0.5;

  // Least contrast (grey levels) between the white surround of the marker
  // and its black border. Lower finds markers in dim or foggy images, at a
  // higher risk of reading noise as a code.
  double min_contrast = 20;

  // Every sample of the quiet zone (half a cell outside each side, and
  // beside each corner) must reach black + this fraction of the contrast.
  // This rejects markers whose outline an occluder grazes near a corner, and
  // grey occluders lying on the quiet zone, which the side fit alone may
  // accept. Higher rejects more of those, but also markers under a strong
  // lighting gradient or vignetting across their surround.
  double min_quiet_zone_level = 0.7;

  // A cell is "uncertain" when its mean is within this fraction of the
  // contrast of the black/white threshold. Each uncertain code cell counts
  // as a corrected bit; an uncertain border cell counts as a border error.
  // Larger rejects more clutter (whose cells are rarely clean black or white)
  // and more badly blurred markers.
  double min_cell_margin = 0.12;

  // Border cells (of the 20) that may be white or uncertain. 0: an occluded
  // or wrongly cornered marker is never read. Larger tolerates specular
  // highlights on the border, at a higher false-detection rate.
  int max_border_errors = 0;

  // Most code bits the decoder may correct; -1 uses the codebook's guarantee
  // (Codebook::correctable_bits()). 0 makes false detections rarer still but
  // loses markers with one misread cell (noise, blur at 1 m).
  int max_bits_corrected = -1;
};

struct Detection {
  int id = -1;       // codebook id
  int rotation = 0;  // quarter turns clockwise of the observed code (Codebook::decode)
  // Corners in the order A, B, C, D of the target layout (top-left,
  // top-right, bottom-right, bottom-left of the printed marker), distorted
  // pixels, OpenCV pixel convention.
  std::array<Eigen::Vector2d, 4> corners_px;
  struct Quality {
    double contrast = 0;              // white surround minus black border, grey levels (8-bit)
    int bits_corrected = 0;           // code bits corrected (uncertain cells included)
    double edge_fit_residual_px = 0;  // RMS of the edge samples about their fitted sides, px
  } quality;
};

// Counts of what happened to the candidates of one image, for diagnostics and
// tests. Every candidate ends in exactly one bucket.
struct DetectorStats {
  int contours = 0;             // contours found (steps 1-3)
  int candidates = 0;           // convex near-right-angled quadrilaterals (steps 4-7)
  int suppressed = 0;           // inside an already detected marker: not refined
  int cut_by_image_border = 0;  // a side or its search window leaves the image
  int side_not_supported = 0;   // a side's edge is missing or broken (occlusion)
  int edge_fit_failed = 0;      // degenerate fit, residual too high, or corners moved too far
  int no_code = 0;              // contrast, border or code check failed
  int duplicates = 0;           // a second detection of a marker already detected
  int detected = 0;
};

class Detector {
 public:
  // Copies the camera and the codebook (both are small). The camera must be
  // the calibration of the images passed to detect(): its distortion shapes
  // the sides. Throws std::invalid_argument naming the parameter when a
  // parameter is out of range (negative sizes, fractions outside [0, 1]).
  Detector(const Camera& camera, const Codebook& codebook, DetectorParameters parameters = {});

  // Detects and identifies the markers in `image`: 8-bit grey (the fast
  // path), or 8-bit BGR/BGRA, or 16-bit, or 32-bit float, which are converted
  // to 8-bit grey first (16-bit and float are scaled so that their maximum
  // becomes 255 when it exceeds 255, resp. 1.0). An empty image, or one too
  // small to hold a marker, gives no detections. Detections are ordered by
  // id, then by position. The image should have the camera's size; a
  // different size is processed as is (the camera model is applied as if it
  // matched). `stats`, when given, receives the candidate counts.
  // Throws std::invalid_argument for an image type it cannot convert.
  std::vector<Detection> detect(const cv::Mat& image, DetectorStats* stats = nullptr) const;

  const DetectorParameters& parameters() const { return parameters_; }
  const Camera& camera() const { return camera_; }
  const Codebook& codebook() const { return codebook_; }

 private:
  Camera camera_;
  Codebook codebook_;
  DetectorParameters parameters_;
};

// Converts an image of any type detect() accepts to 8-bit grey (no copy when
// it already is). Throws std::invalid_argument naming the type otherwise.
cv::Mat to_gray8(const cv::Mat& image);

}  // namespace vision
