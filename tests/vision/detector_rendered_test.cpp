// The detector on frames of sim::scene::SceneRenderer: the paper's
// camera (736x571, its intrinsics and distortion) and sheet (5 cm markers),
// the pose marker at 0.10-1.00 m anywhere in the image, tilt up to 40 degrees,
// the renderer's realistic optics and sensor (blur 0.6 px, vignetting,
// lighting gradient, shot and read noise, 8-bit quantization).
//
// Each test renders its own frames (ctest runs every test in its own process,
// so nothing is shared); frame counts keep the whole file near 40 s of CPU.
// Poses and sensor noise come from fixed seeds, so every run judges the same
// frames: the bars below are the detector's targets, met on this sample.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "detector_frames.hpp"
#include "sim/scene/renderer.hpp"
#include "vision/detector.hpp"

namespace {

using detector_test::corner_rms;
using detector_test::distance_class;

// A marker "should be detected" when the renderer says its whole outline is
// visible and the outline keeps this far from the image border: the detector
// reads the edge profile up to edge_search_px + 1 px (6 px) outside the
// outline, so nearer the border the edge cannot be measured on both sides.
constexpr double kDetectableBorderPx = 8.0;

struct Tally {
  int detectable = 0;  // fully visible, kDetectableBorderPx from the border
  int found = 0;       // of those, detected with the right id
  int cut = 0;         // truth markers cut by the image border (not occluded)
  int cut_detected = 0;
  int occluded = 0;  // truth markers an occluder covers or comes within 3 sigma + 1 px of
  int occluded_detected = 0;
  double occluded_worst_rms = 0;  // over the occluded markers that were detected
  int false_detections = 0;       // a detection no visible marker explains
  double sum_sq[3] = {0, 0, 0};
  int corners[3] = {0, 0, 0};  // detections per distance class
  double worst_rms = 0;
};

// A detection "explains" a truth marker when the ids agree and the corners
// lie within 2 px (RMS): far above any sub-pixel error, far below a marker.
void tally_frame(const sim::scene::RenderedFrame& frame, const vision::Pose& T,
                 const vision::Target& target, const std::vector<vision::Detection>& detections,
                 Tally* t) {
  std::vector<bool> explained(detections.size(), false);
  for (const auto& truth : frame.markers) {
    const auto& m = target.marker(truth.id);
    const double distance = (T * Eigen::Vector3d(m.centre_m.x(), m.centre_m.y(), 0)).norm();
    int hit = -1;
    for (size_t k = 0; k < detections.size(); ++k)
      if (detections[k].id == truth.id &&
          corner_rms(detections[k].corners_px, truth.corners_px) < 2)
        hit = static_cast<int>(k);
    if (!truth.fully_visible) {
      // A detection of the id elsewhere is a false detection (counted below).
      if (truth.occluded) {
        ++t->occluded;
        if (hit >= 0) {
          ++t->occluded_detected;
          t->occluded_worst_rms = std::max(
              t->occluded_worst_rms, corner_rms(detections[hit].corners_px, truth.corners_px));
        }
      } else {
        ++t->cut;
        if (hit >= 0) ++t->cut_detected;
      }
      continue;
    }
    if (truth.border_distance_px >= kDetectableBorderPx) ++t->detectable;
    if (hit < 0) continue;
    explained[hit] = true;
    if (truth.border_distance_px >= kDetectableBorderPx) ++t->found;
    const double rms = corner_rms(detections[hit].corners_px, truth.corners_px);
    const int c = distance_class(distance);
    t->sum_sq[c] += rms * rms;
    ++t->corners[c];
    t->worst_rms = std::max(t->worst_rms, rms);
  }
  for (size_t k = 0; k < detections.size(); ++k)
    if (!explained[k]) {
      bool cut_marker = false;  // a detection of a cut marker is counted above
      for (const auto& truth : frame.markers)
        cut_marker = cut_marker || (!truth.fully_visible && truth.id == detections[k].id &&
                                    corner_rms(detections[k].corners_px, truth.corners_px) < 2);
      if (!cut_marker) ++t->false_detections;
    }
}

// The detector's bars (vision/detector.hpp): detection rate >= 99.5 %, corner RMS <= 0.07 px in
// every distance class, and no false detection.
void expect_issue_targets(const Tally& t) {
  EXPECT_GE(static_cast<double>(t.found) / t.detectable, 0.995)
      << t.found << " of " << t.detectable;
  for (int c = 0; c < 3; ++c)
    EXPECT_LE(std::sqrt(t.sum_sq[c] / std::max(t.corners[c], 1)), 0.07)
        << detector_test::distance_class_name(c);
  EXPECT_EQ(t.false_detections, 0);
}

class DetectorRendered : public ::testing::Test {
 protected:
  DetectorRendered()
      : camera_(vision::Camera::paper_default()),
        target_(vision::Target::paper_default()),
        detector_(camera_, codebook_) {}

  Tally run(const sim::scene::SceneOptions& options, int frames, uint64_t seed) const {
    const sim::scene::SceneRenderer renderer(camera_, target_, codebook_, options);
    const auto poses = detector_test::sample_poses(camera_, frames, seed);
    Tally t;
    for (int i = 0; i < frames; ++i) {
      const sim::scene::RenderedFrame frame = renderer.render(poses[i], seed * 100000 + i);
      tally_frame(frame, poses[i], target_, detector_.detect(frame.image), &t);
    }
    return t;
  }

  vision::Camera camera_;
  vision::Target target_;
  vision::Codebook codebook_;
  vision::Detector detector_;
};

// Detection rate >= 99.5 %. 500 frames hold ~1,400 detectable
// markers, so the bound allows 7 misses.
TEST_F(DetectorRendered, DetectsAtLeast99Point5PercentOfVisibleMarkers) {
  const Tally t = run(sim::scene::SceneOptions{}, 500, 11);
  ASSERT_GT(t.detectable, 1000);
  const double rate = static_cast<double>(t.found) / t.detectable;
  RecordProperty("detectable", t.detectable);
  RecordProperty("detection_rate", std::to_string(rate));
  EXPECT_GE(rate, 0.995) << t.found << " of " << t.detectable;
  EXPECT_EQ(t.false_detections, 0);
}

// The corner target is 0.07 px RMS in every distance class;
// the test holds the detector to it per class (each class gets 150-300
// detections, so the RMS itself is known to ~5 %), and no single marker may
// be off by more than 0.5 px (a corner placed from the wrong edge would be
// off by pixels).
TEST_F(DetectorRendered, CornerRmsIsWithinTheTargetInEveryDistanceClass) {
  const Tally t = run(sim::scene::SceneOptions{}, 300, 12);
  for (int c = 0; c < 3; ++c) {
    ASSERT_GT(t.corners[c], 50) << detector_test::distance_class_name(c);
    const double rms = std::sqrt(t.sum_sq[c] / t.corners[c]);
    RecordProperty(std::string("corner_rms_px_") + detector_test::distance_class_name(c),
                   std::to_string(rms));
    EXPECT_LE(rms, 0.07) << detector_test::distance_class_name(c);
  }
  EXPECT_LE(t.worst_rms, 0.5);
}

// Markers cut by the image border are rejected, not mis-cornered. In this
// frame set the three measurement markers of the sheet leave the image at
// close range, so there are hundreds of cut markers.
TEST_F(DetectorRendered, MarkersCutByTheImageBorderAreNotDetected) {
  const Tally t = run(sim::scene::SceneOptions{}, 150, 13);
  ASSERT_GT(t.cut, 50);
  EXPECT_EQ(t.cut_detected, 0) << "of " << t.cut << " cut markers";
  EXPECT_EQ(t.false_detections, 0);
}

// Opaque bars (8-40 px wide) across marker outlines: an occluded marker is
// rejected, never mis-cornered, and the others are still found. The
// renderer calls a marker occluded also when a bar merely comes within
// 3 sigma + 1 = 2.8 px of its outline without touching it; such a marker may
// be detected, but then its corners must be as good as an unoccluded
// marker's (0.07 px), and such near misses are rare (<= 1 %).
TEST_F(DetectorRendered, OccludedMarkersAreRejectedNotMisCornered) {
  sim::scene::SceneOptions o;
  o.occluders = 2;
  const Tally t = run(o, 200, 14);
  ASSERT_GT(t.occluded, 150);
  EXPECT_LE(t.occluded_detected, t.occluded / 100) << "of " << t.occluded << " occluded markers";
  EXPECT_LE(t.occluded_worst_rms, 0.07);
  EXPECT_EQ(t.cut_detected, 0);
  EXPECT_EQ(t.false_detections, 0);
  EXPECT_GE(static_cast<double>(t.found) / t.detectable, 0.99);
}

// A noisier sensor (full well 3,000 e-, read noise 30 e-: about 5 grey
// levels of noise on the paper, three times the default): Canny's smoothing
// keeps the outlines closed, and the corners stay within the target.
TEST_F(DetectorRendered, NoisySensorKeepsDetectionAndCornerAccuracy) {
  sim::scene::SceneOptions o;
  o.full_well_electrons = 3000;
  o.read_noise_electrons = 30;
  const Tally t = run(o, 150, 17);
  expect_issue_targets(t);
}

// A 5 MP GigE camera (2448x2048): the paper's camera scaled per axis (fx, cx
// by 2448/736, fy, cy by 2048/571, the same lens distortion), so the same
// field of view, poses and markers, each 3.3-3.6 times larger in pixels, with
// the renderer's default optics and sensor. The detector keeps its bars in
// pixels: a side's corner error is set by the per-sample edge noise (the same
// blur and grey-level noise per pixel) and the number of samples per side
// (max_edge_samples_per_side, reached by nearly every side here), not by the
// marker's size, so the 0.07 px per distance class of 736x571 applies
// unchanged (measured on these frames: 0.006-0.011 px). Detection: the same
// 99.5 % bar, which for the 82 detectable markers of these 30 frames allows
// no miss. Seeded frames, so the outcome is fixed.
TEST(DetectorRendered5MP, KeepsDetectionRateAndCornerAccuracyAt2448x2048) {
  const vision::Camera paper = vision::Camera::paper_default();
  const double sx = 2448.0 / paper.width_px(), sy = 2048.0 / paper.height_px();
  vision::Intrinsics k = paper.intrinsics();
  k.fx *= sx;
  k.fy *= sy;
  k.cx = (k.cx + 0.5) * sx - 0.5;  // pixel centres scale about the image's corner
  k.cy = (k.cy + 0.5) * sy - 0.5;
  const vision::Camera camera(k, paper.distortion(), 2448, 2048);
  const vision::Target target = vision::Target::paper_default();
  const vision::Codebook codebook;
  const vision::Detector detector(camera, codebook);
  const sim::scene::SceneRenderer renderer(camera, target, codebook);
  constexpr int kFrames = 30;
  const auto poses = detector_test::sample_poses(camera, kFrames, 41);
  Tally t;
  for (int i = 0; i < kFrames; ++i) {
    const sim::scene::RenderedFrame frame = renderer.render(poses[i], 4100000 + i);
    tally_frame(frame, poses[i], target, detector.detect(frame.image), &t);
  }
  ASSERT_GT(t.detectable, 60);
  for (int c = 0; c < 3; ++c)  // each class's RMS known to ~15 % or better
    ASSERT_GT(t.corners[c], 20) << detector_test::distance_class_name(c);
  expect_issue_targets(t);
  EXPECT_LE(t.worst_rms, 0.5);
  EXPECT_EQ(t.cut_detected, 0);
}

// Heavier defocus (PSF sigma 1.5 px instead of 0.6): the symmetric blur
// widens the edges but does not move them; the corners stay within the target.
TEST_F(DetectorRendered, HeavierBlurKeepsDetectionAndCornerAccuracy) {
  sim::scene::SceneOptions o;
  o.blur_sigma_px = 1.5;
  const Tally t = run(o, 150, 18);
  expect_issue_targets(t);
}

// The detector keeps its accuracy when the sheet is cut one
// quiet-zone cell outside the marker (a marker printed alone with `rig
// marker`, on a darker background): the paper edge lies one cell (6-60 px)
// outside the marker's edge, beyond the edge fit's window.
TEST_F(DetectorRendered, MarkerOnASheetCutAtItsQuietZoneKeepsItsAccuracy) {
  vision::Target alone;
  alone.name = "one marker";
  alone.markers = {vision::TargetMarker{0, 0.05, Eigen::Vector2d::Zero()}};
  alone.pose_marker_id = 0;
  const double half = 0.025 + 0.05 / 6 + 1e-4;  // border + one cell of quiet zone (+0.1 mm)
  alone.sheet_width_m = alone.sheet_height_m = 2 * half;
  alone.sheet_origin_m = Eigen::Vector2d(-half, -half);
  alone.quiet_cells = 1;
  alone.validate();
  const sim::scene::SceneRenderer renderer(camera_, alone, codebook_);
  const auto poses = detector_test::sample_poses(camera_, 200, 20);
  Tally t;
  for (int i = 0; i < 200; ++i) {
    const sim::scene::RenderedFrame frame = renderer.render(poses[i], 2000000 + i);
    tally_frame(frame, poses[i], alone, detector_.detect(frame.image), &t);
  }
  ASSERT_GT(t.detectable, 150);
  expect_issue_targets(t);
}

// Candidates at half resolution (the default) or at full resolution (the
// paper's pipeline literally): the corners come from the same full-image edge
// fit, so where both find a marker they agree to far below the corner target
// (0.005 px, a tenth of the per-class RMS). Half resolution may lose a
// marker that full resolution finds (small or at the image border), rarely.
TEST_F(DetectorRendered, HalfResolutionCandidatesGiveTheSameCornersAsFullResolution) {
  vision::DetectorParameters full;
  full.candidate_decimation = 1;
  const vision::Detector paper(camera_, codebook_, full);
  const sim::scene::SceneRenderer renderer(camera_, target_, codebook_);
  const auto poses = detector_test::sample_poses(camera_, 80, 19);
  int both = 0, only_one = 0;
  for (int i = 0; i < 80; ++i) {
    const cv::Mat image = renderer.render(poses[i], 1900000 + i).image;
    const auto half = detector_.detect(image), whole = paper.detect(image);
    int matched = 0;
    for (const auto& x : half)
      for (const auto& y : whole)
        if (y.id == x.id && corner_rms(x.corners_px, y.corners_px) < 2) {
          ++matched;
          EXPECT_LT(corner_rms(x.corners_px, y.corners_px), 0.005) << "frame " << i;
        }
    both += matched;
    only_one += static_cast<int>(half.size() + whole.size()) - 2 * matched;
  }
  EXPECT_GT(both, 150);
  EXPECT_LE(only_one, both / 100) << "of " << both;
}

// Zero false detections over >= 1,000 clutter-only frames
// (rectangles, quadrilaterals, ellipses, lines, checker patches) at the
// default setting.
TEST_F(DetectorRendered, ClutterOnlyFramesGiveNoDetections) {
  sim::scene::SceneOptions o;
  o.show_target = false;
  o.clutter_shapes = 40;
  const sim::scene::SceneRenderer renderer(camera_, target_, codebook_, o);
  const auto poses = detector_test::sample_poses(camera_, 1000, 15);
  int false_detections = 0, candidates = 0;
  for (int i = 0; i < 1000; ++i) {
    vision::DetectorStats stats;
    false_detections += static_cast<int>(
        detector_.detect(renderer.render(poses[i], 1500000 + i).image, &stats).size());
    candidates += stats.candidates;
  }
  RecordProperty("candidates", candidates);
  // The clutter must produce quadrilaterals for the test to mean anything.
  EXPECT_GT(candidates, 1000);
  EXPECT_EQ(false_detections, 0);
}

// Clutter around the sheet does not hide markers nor add detections.
TEST_F(DetectorRendered, ClutterAroundTheSheetAddsNoDetections) {
  sim::scene::SceneOptions o;
  o.clutter_shapes = 40;
  const Tally t = run(o, 150, 16);
  EXPECT_EQ(t.false_detections, 0);
  EXPECT_GE(static_cast<double>(t.found) / t.detectable, 0.99);
}

}  // namespace

// A marker whose whole outline is in view with the white beyond its outer
// edges (3.1-3.6 px from the image border: image_border_margin_px 1 +
// min_edge_window_px 2 + a profile step) is measured: its edge windows are cut
// where the image ends instead of rejecting it. Its corners are as good as
// elsewhere (the realistic scene, blur 0.6 px: the cut window's white end
// lies 2 px = 3 sigma beyond the edge, on the plateau); 0.15 px bounds the
// seeded noise's corner error of ~0.03 px RMS with room for the shortened
// window. Nearer the border (1.5 px) it is cut by it, never mis-cornered.
TEST(DetectorNearBorder, MarkerThreePixelsFromTheBorderIsMeasured) {
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::Target target = vision::Target::paper_default();
  const sim::scene::SceneRenderer renderer(camera, target, vision::Codebook(), {});
  const vision::Detector detector(camera, vision::Codebook());
  // The pose marker (id 0) head-on at 0.3 m, moved right until its outline's
  // distance to the border is `wanted` px (bisection on the lateral offset).
  const auto placed = [&](double wanted) {
    vision::Pose T;
    T.t = Eigen::Vector3d(0, 0.01, 0.3);
    double lo = 0, hi = 0.2;
    for (int i = 0; i < 60; ++i) {
      T.t.x() = -0.5 * (lo + hi);  // the camera sees the marker move right as the target moves left
      const double d = renderer.ground_truth(T)[0].border_distance_px;
      (d > wanted ? lo : hi) = 0.5 * (lo + hi);
    }
    return T;
  };
  int measured = 0;
  for (const double wanted : {3.2, 3.5}) {
    for (const uint64_t seed : {1u, 2u, 3u}) {
      const vision::Pose T = placed(wanted);
      const sim::scene::RenderedFrame frame = renderer.render(T, seed);
      ASSERT_NEAR(frame.markers[0].border_distance_px, wanted, 0.01);
      ASSERT_TRUE(frame.markers[0].fully_visible);
      for (const vision::Detection& d : detector.detect(frame.image)) {
        if (d.id != 0) continue;
        EXPECT_LT(detector_test::corner_rms(d.corners_px, frame.markers[0].corners_px), 0.15)
            << wanted;
        ++measured;
      }
    }
  }
  EXPECT_EQ(measured, 6);
  const vision::Pose T = placed(1.5);
  const sim::scene::RenderedFrame frame = renderer.render(T, 4);
  vision::DetectorStats stats;
  for (const vision::Detection& d : detector.detect(frame.image, &stats))
    EXPECT_NE(d.id, 0) << "a marker 1.5 px from the border cannot be measured";
  EXPECT_GT(stats.cut_by_image_border, 0);
}
