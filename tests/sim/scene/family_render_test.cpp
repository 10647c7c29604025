// sim::scene renders a target in its own marker family: a rendered frame of
// an ArUco target is read by cv::aruco with the layout's ids and with
// corners at the renderer's projected truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <opencv2/aruco.hpp>

#include "sim/scene/renderer.hpp"
#include "vision/marker_family.hpp"
#include "vision/pose.hpp"

namespace sim::scene {
namespace {

// Bound on each corner's distance to the truth: 0.5 px. The renderer
// integrates the printed cells exactly over each pixel, so the image's corner
// is the projected corner blurred by the default PSF (sigma 0.6 px) and 8-bit
// sensor noise. cv::cornerSubPix (CORNER_REFINE_SUBPIX) on a blurred corner
// whose angle is 90 deg +- d (d < 25 deg at these tilts) is biased by about
// sigma * tan(d / 2) < 0.14 px; the noise term is sigma_DN / (contrast *
// sqrt(window samples)) ~ 3 / (150 * 7) < 0.01 px. Seeded render: the
// frames, hence the result, are deterministic.
constexpr double kCornerBoundPx = 0.5;

vision::Pose tilted(double distance_m, double yaw_deg, double pitch_deg) {
  constexpr double kDeg = 3.14159265358979323846 / 180;
  vision::Pose T;
  T.R = vision::rotation_from_euler_zyx(0, yaw_deg * kDeg, pitch_deg * kDeg);
  T.t = {0, 0, distance_m};
  return T;
}

TEST(FamilyRender, ArucoTargetFrameIsReadByCvArucoAtTheProjectedCorners) {
  const vision::Camera camera = vision::Camera::paper_default();
  vision::Target target = vision::Target::paper_default();
  target.family = "aruco:DICT_6X6_250";
  const SceneRenderer renderer(camera, target, vision::MarkerFamily::named(target.family));
  cv::Ptr<cv::aruco::DetectorParameters> params = cv::aruco::DetectorParameters::create();
  params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  int seed = 100;
  double worst_px = 0;
  for (const vision::Pose& T : {tilted(0.45, 0, 0), tilted(0.5, 20, -10), tilted(0.55, -15, 15)}) {
    const RenderedFrame frame = renderer.render(T, static_cast<uint64_t>(seed++));
    std::vector<int> ids;
    std::vector<std::vector<cv::Point2f>> corners;
    cv::aruco::detectMarkers(frame.image,
                             cv::aruco::getPredefinedDictionary(cv::aruco::DICT_6X6_250), corners,
                             ids, params);
    std::vector<int> visible;
    for (const MarkerTruth& truth : frame.markers) {
      if (!truth.fully_visible) continue;
      visible.push_back(truth.id);
      const auto it = std::find(ids.begin(), ids.end(), truth.id);
      ASSERT_NE(it, ids.end()) << "id " << truth.id << " not found, seed " << seed - 1;
      const auto& found = corners[static_cast<size_t>(it - ids.begin())];
      // cv::aruco's corner order is the printed top-left, top-right,
      // bottom-right, bottom-left: the layout's A, B, C, D.
      for (int k = 0; k < 4; ++k) {
        const double err = (Eigen::Vector2d(found[k].x, found[k].y) - truth.corners_px[k]).norm();
        EXPECT_LT(err, kCornerBoundPx) << "id " << truth.id << " corner " << k;
        worst_px = std::max(worst_px, err);
      }
    }
    std::sort(ids.begin(), ids.end());
    std::sort(visible.begin(), visible.end());
    EXPECT_FALSE(visible.empty());
    EXPECT_EQ(ids, visible) << "seed " << seed - 1;
  }
  std::printf("largest corner error %.3f px (bound %.1f px)\n", worst_px, kCornerBoundPx);
}

}  // namespace
}  // namespace sim::scene
