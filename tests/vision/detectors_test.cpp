// The detector registry (vision/detectors.hpp): which detector reads which
// family, the equivalences it relies on, its errors, and every detector on
// rendered frames of every family it reads: the ids found against the
// renderer's visible markers and the corners against its projected truth.
#include "vision/detectors.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <opencv2/aruco.hpp>
#include <thread>

#include "sim/scene/renderer.hpp"
#include "vision/marker_family.hpp"
#include "vision/pose.hpp"

namespace vision {
namespace {

// Whether every id of an OpenCV predefined dictionary has the cells of the
// same id of `family` turned clockwise by `quarter_turns`.
bool same_cells(const MarkerFamily& family, cv::aruco::PREDEFINED_DICTIONARY_NAME which,
                int quarter_turns) {
  const cv::Ptr<cv::aruco::Dictionary> d = cv::aruco::getPredefinedDictionary(which);
  if (d->bytesList.rows != family.size() || d->markerSize != family.code_cells()) return false;
  for (int id = 0; id < family.size(); ++id) {
    const cv::Mat bits = cv::aruco::Dictionary::getBitsFromByteList(
        d->bytesList.rowRange(id, id + 1), d->markerSize);
    const int n = d->markerSize;
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) {
        int rr = r, cc = c;  // the family's cell that lands on (r, c) after the turns
        for (int k = 0; k < quarter_turns; ++k) {
          const int t = rr;
          rr = n - 1 - cc;
          cc = t;
        }
        if ((bits.at<uint8_t>(r, c) != 0) != family.cell_is_white(id, rr + 1, cc + 1)) return false;
      }
  }
  return true;
}

TEST(DetectorRegistry, LibraryFamiliesItReadsThroughAnotherAreTheSameCodesAndIds) {
  // cv::aruco reads apriltag:* through DICT_APRILTAG_*, libapriltag reads
  // aruco:DICT_APRILTAG_36h11 through tag36h11: every id must be the same
  // printed marker, turned by 180 degrees (the two corner orders the
  // detectors correct for), and by no other turn.
  for (const auto& [name, dict] : {std::pair{"apriltag:tag36h11", cv::aruco::DICT_APRILTAG_36h11},
                                   std::pair{"apriltag:tag16h5", cv::aruco::DICT_APRILTAG_16h5}}) {
    EXPECT_TRUE(same_cells(MarkerFamily::named(name), dict, 2)) << name;
    EXPECT_FALSE(same_cells(MarkerFamily::named(name), dict, 0)) << name;
  }
  EXPECT_TRUE(same_cells(MarkerFamily::named("aruco:DICT_APRILTAG_36h11"),
                         cv::aruco::DICT_APRILTAG_36h11, 0));
}

TEST(DetectorRegistry, EveryFamilyHasADetectorAndRigsReadsOnlyRig4x4) {
  EXPECT_EQ(detector_names().front(), "rig");
  for (const std::string& family : MarkerFamily::names())
    EXPECT_FALSE(detectors_for_family(family).empty()) << family;
  EXPECT_EQ(detectors_for_family("rig4x4").front(), "rig");
  EXPECT_FALSE(detector_reads("rig", "aruco:DICT_4X4_50"));
  EXPECT_FALSE(detector_reads("apriltag:d2", "aruco:DICT_6X6_250"));
  EXPECT_TRUE(detector_reads("aruco:subpix", "apriltag:tag16h5"));
  EXPECT_TRUE(detectors_for_family("no-such-family").empty());
}

TEST(DetectorRegistry, UnknownNamesAndUnreadableFamiliesAreNamedInTheError) {
  const Camera camera = Camera::paper_default();
  try {
    make_detector("aruco:fast", camera, "rig4x4");
    FAIL() << "an unknown detector was made";
  } catch (const DetectorRegistryError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("\"aruco:fast\""), std::string::npos) << what;
    EXPECT_NE(what.find("\"aruco:subpix\""), std::string::npos) << what;
  }
  try {
    make_detector("rig", camera, "aruco:DICT_6X6_250");
    FAIL() << "rig's detector accepted an ArUco family";
  } catch (const DetectorRegistryError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("\"aruco:DICT_6X6_250\""), std::string::npos) << what;
    EXPECT_NE(what.find("\"aruco:none\""), std::string::npos) << what;   // who can
    EXPECT_EQ(what.find("\"apriltag:d1\""), std::string::npos) << what;  // who cannot
  }
  try {
    make_detector("apriltag:d1", camera, "no-such-family");
    FAIL() << "a family nobody reads was accepted";
  } catch (const DetectorRegistryError& e) {
    EXPECT_NE(std::string(e.what()).find("no detector decodes it"), std::string::npos) << e.what();
  }
}

TEST(DetectorRegistry, QuarterTurnsFollowTheDirectionOfAToB) {
  const Eigen::Vector2d o(100, 100);
  auto square = [&](Eigen::Vector2d ab) {
    const Eigen::Vector2d ad(-ab.y(), ab.x());  // y down: +90 degrees is clockwise
    return std::array<Eigen::Vector2d, 4>{o, o + ab, o + ab + ad, o + ad};
  };
  EXPECT_EQ(quarter_turns_of(square({10, 1})), 0);
  EXPECT_EQ(quarter_turns_of(square({-1, 10})), 1);
  EXPECT_EQ(quarter_turns_of(square({-10, 0})), 2);
  EXPECT_EQ(quarter_turns_of(square({2, -10})), 3);
}

Pose tilted(double distance_m, double yaw_deg, double pitch_deg, double roll_deg) {
  constexpr double kDeg = 3.14159265358979323846 / 180;
  Pose T;
  T.R = rotation_from_euler_zyx(roll_deg * kDeg, yaw_deg * kDeg, pitch_deg * kDeg);
  T.t = {0.01, -0.005, distance_m};
  return T;
}

// What one detector did on the rendered frames of one family.
struct Tally {
  int visible = 0, found = 0, false_ids = 0;
  double sum_sq_px = 0;
  int corners = 0;
  Eigen::Vector2d sum_px = Eigen::Vector2d::Zero();  // mean signed error: the convention
  double worst_px = 0;
};

Tally run_detector(const FiducialDetector& detector,
                   const std::vector<sim::scene::RenderedFrame>& frames) {
  Tally t;
  for (const auto& frame : frames) {
    const std::vector<Detection> found = detector.detect(frame.image);
    for (const Detection& d : found) {
      const auto truth =
          std::find_if(frame.markers.begin(), frame.markers.end(),
                       [&](const sim::scene::MarkerTruth& m) { return m.id == d.id; });
      double rms = 0;
      if (truth != frame.markers.end())
        for (size_t k = 0; k < 4; ++k)
          rms += (d.corners_px[k] - truth->corners_px[k]).squaredNorm() / 4;
      // Not that marker: an id not in view, or at the wrong place (a quad
      // of code cells decoded as a marker). 5 px is far beyond any corner
      // error of a true detection (the bounds below) and far below a side.
      if (truth == frame.markers.end() || !truth->fully_visible || std::sqrt(rms) > 5) {
        ++t.false_ids;
        continue;
      }
      for (size_t k = 0; k < 4; ++k) {
        const Eigen::Vector2d e = d.corners_px[k] - truth->corners_px[k];
        t.sum_sq_px += e.squaredNorm();
        t.sum_px += e;
        t.worst_px = std::max(t.worst_px, e.norm());
        ++t.corners;
      }
    }
    for (const auto& m : frame.markers) {
      if (!m.fully_visible || m.border_distance_px < 8) continue;
      ++t.visible;
      t.found +=
          std::any_of(found.begin(), found.end(), [&](const Detection& d) { return d.id == m.id; });
    }
  }
  return t;
}

// Largest corner error of a true detection, px, on these renders (the
// renderer's default PSF sigma 0.6 px, 8-bit sensor noise, markers of 60-100
// px a side, tilts up to 25 degrees). Each is the detector's own corner model:
//  - rig: edge lines fitted to sub-pixel edge samples through the lens
//    model; its own tests hold it to 0.05 px RMS (detector_rendered_test).
//  - cv::cornerSubPix (aruco:subpix): biased by ~sigma tan(d / 2) < 0.14 px
//    for a corner angle 90 +- d deg (d < 25), noise < 0.01 px
//    (family_render_test derives it): 0.5 px.
//  - AprilTag's edge refinement (apriltag:*, aruco:apriltag): lines through
//    gradient samples along each side, on pixels, not through the lens
//    model, so a side's curvature (<0.2 px over a marker here) enters: 1 px.
//  - aruco:none and aruco:contour: the corners of the thresholded contour,
//    which runs through the centres of the outermost dark pixels, 0..1 px
//    inside each side: up to sqrt(2) px along the diagonal, plus the
//    polygon fit's rounding: 2 px.
double corner_bound_px(const std::string& detector) {
  if (detector == "rig") return 0.05;
  if (detector == "aruco:subpix") return 0.5;
  if (detector == "aruco:none" || detector == "aruco:contour") return 2.0;
  return 1.0;
}

// Bound on each axis of the mean signed corner error, px: what a pixel
// convention error would shift (0.5 px on both axes). A detector's inward or
// outward bias points along each corner's diagonal and cancels over the
// four corners of a marker; what remains is noise and tilt asymmetry, a few
// hundredths of a pixel here.
constexpr double kConventionBoundPx = 0.15;

TEST(DetectorRegistry, EveryDetectorReadsRenderedFramesOfEveryFamilyItDecodes) {
  const Camera camera = Camera::paper_default();
  for (const std::string& family : MarkerFamily::names()) {
    Target target = Target::paper_default();
    target.family = family;
    const sim::scene::SceneRenderer renderer(camera, target, MarkerFamily::named(family));
    std::vector<sim::scene::RenderedFrame> frames;
    uint64_t seed = 200;
    for (const Pose& T :
         {tilted(0.45, 0, 0, 0), tilted(0.5, 20, -10, 35), tilted(0.55, -15, 15, 100),
          tilted(0.4, 5, 25, 190), tilted(0.6, -25, -5, 280)})
      frames.push_back(renderer.render(T, seed++));
    for (const std::string& name : detectors_for_family(family)) {
      const auto detector = make_detector(name, camera, family);
      const Tally t = run_detector(*detector, frames);
      const Eigen::Vector2d mean = t.sum_px / std::max(1, t.corners);
      std::printf("%-26s %-15s found %2d/%2d false %d rms %.3f worst %.3f mean (%+.3f, %+.3f)\n",
                  family.c_str(), name.c_str(), t.found, t.visible, t.false_ids,
                  std::sqrt(t.sum_sq_px / std::max(1, t.corners)), t.worst_px, mean.x(), mean.y());
      const std::string what = name + " on " + family;
      // Every marker in view with 8 px of white beyond it is found (the
      // renders are seeded: deterministic).
      EXPECT_EQ(t.found, t.visible) << what;
      EXPECT_GT(t.visible, 3 * static_cast<int>(frames.size())) << what;
      EXPECT_LT(t.worst_px, corner_bound_px(name)) << what;
      EXPECT_LT(std::abs(mean.x()), kConventionBoundPx) << what;
      EXPECT_LT(std::abs(mean.y()), kConventionBoundPx) << what;
      // False detections: none, but for libapriltag on the 16-bit families,
      // where a quad of code cells decodes with p = 4 n / 2^16 = 0.2 %
      // (detectors_apriltag.cpp); at ~100 such quads a frame that is 0.2
      // per frame: bounded by one per frame.
      const bool sixteen_bit = family == "rig4x4" || family == "apriltag:tag16h5";
      if (name.rfind("apriltag:", 0) == 0 && sixteen_bit)
        EXPECT_LE(t.false_ids, static_cast<int>(frames.size())) << what;
      else
        EXPECT_EQ(t.false_ids, 0) << what;
    }
  }
}

// detect() is const and may run from several threads on one detector (the
// sweep measures whole frames in parallel): each thread gets exactly the
// detections a single caller gets. libapriltag's detectors come from a pool.
TEST(DetectorRegistry, OneDetectorDetectsTheSameFromSeveralThreadsAtOnce) {
  const Camera camera = Camera::paper_default();
  const Target target = Target::paper_default();
  const sim::scene::SceneRenderer renderer(camera, target, MarkerFamily::named(target.family));
  const cv::Mat image = renderer.render(tilted(0.5, 10, -5, 20), 7).image;
  for (const std::string name : {"apriltag:d2", "aruco:subpix"}) {
    const auto detector = make_detector(name, camera, target.family);
    const std::vector<Detection> alone = detector->detect(image);
    ASSERT_FALSE(alone.empty()) << name;
    std::vector<std::vector<Detection>> got(3);
    std::vector<std::thread> threads;
    for (auto& g : got)
      threads.emplace_back([&] {
        for (int k = 0; k < 3; ++k)
          g = detector->detect(image);
      });
    for (auto& t : threads)
      t.join();
    for (const auto& g : got) {
      ASSERT_EQ(g.size(), alone.size()) << name;
      for (size_t i = 0; i < g.size(); ++i) {
        EXPECT_EQ(g[i].id, alone[i].id) << name;
        for (size_t k = 0; k < 4; ++k)
          EXPECT_EQ(g[i].corners_px[k], alone[i].corners_px[k]) << name;  // same arithmetic
      }
    }
  }
}

}  // namespace
}  // namespace vision
