#include "opencv_reference.hpp"

#include <cmath>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>
#include <utility>
#include <vector>

namespace rig_test {
namespace {

using Views = std::map<std::int64_t, std::pair<std::vector<cv::Point3f>, std::vector<cv::Point2f>>>;

Views views_of(const rig::calibrate::CalibrationProblem& p) {
  Views v;
  for (const auto& o : p.corners) {
    v[o.plan_index].first.emplace_back(o.target_point_m.x(), o.target_point_m.y(), 0.0f);
    v[o.plan_index].second.emplace_back(o.pixel.x(), o.pixel.y());
  }
  return v;
}

}  // namespace

OpenCvFit opencv_calibrate(const rig::calibrate::CalibrationProblem& fit,
                           const rig::calibrate::CalibrationProblem& held_out) {
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  for (const auto& [index, view] : views_of(fit)) {
    if (view.first.size() < 8) continue;
    object.push_back(view.first);
    image.push_back(view.second);
  }
  const vision::Camera& nominal = fit.nominal_camera;
  cv::Mat K = nominal.camera_matrix_cv(), dist = nominal.distortion_cv();
  std::vector<cv::Mat> rvecs, tvecs;
  OpenCvFit out;
  // One thread, for a repeatable figure: the focal lengths are
  // ill-conditioned on views that all share one target orientation, and two
  // runs on the same detections, with OpenCV's thread pool, once ended
  // 0.28 px apart in fx.
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  out.rms_px = cv::calibrateCamera(object, image, cv::Size(nominal.width_px(), nominal.height_px()),
                                   K, dist, rvecs, tvecs, cv::CALIB_USE_INTRINSIC_GUESS);
  cv::setNumThreads(threads);
  out.camera = vision::Camera(
      {K.at<double>(0, 0), K.at<double>(1, 1), K.at<double>(0, 2), K.at<double>(1, 2)},
      {dist.at<double>(0), dist.at<double>(1), dist.at<double>(2), dist.at<double>(3),
       dist.at<double>(4)},
      nominal.width_px(), nominal.height_px());
  double sum = 0;
  std::size_t n = 0;
  for (const auto& [index, view] : views_of(held_out)) {
    if (view.first.size() < 4) continue;
    cv::Mat rvec, tvec;
    cv::solvePnP(view.first, view.second, K, dist, rvec, tvec);
    std::vector<cv::Point2f> projected;
    cv::projectPoints(view.first, rvec, tvec, K, dist, projected);
    for (std::size_t i = 0; i < projected.size(); ++i) {
      const cv::Point2f e = projected[i] - view.second[i];
      sum += e.dot(e);
      ++n;
    }
  }
  out.pnp_held_out_rms_px = n == 0 ? 0.0 : std::sqrt(sum / static_cast<double>(n));
  return out;
}

}  // namespace rig_test
