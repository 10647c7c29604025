// The test renderer of detector_synthetic.hpp. Its own file so that it keeps
// the build's optimisation level under the sanitizers, where the test code
// compiles at -O0 (tests/vision/CMakeLists.txt): it does the work its tests
// wait for.
#include "detector_synthetic.hpp"

#include <opencv2/imgproc.hpp>
#include <random>

namespace detector_test {

SyntheticRenderer::SyntheticRenderer(const vision::Camera& camera, const vision::Target& target,
                                     const vision::Codebook& codebook, SyntheticOptions options)
    : camera_(camera), target_(target), codebook_(codebook), o_(options) {
  const int ss = o_.supersampling, w = camera.width_px() * ss, h = camera.height_px() * ss;
  rays_.resize(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const Eigen::Vector2d px(-0.5 + (x + 0.5) / ss, -0.5 + (y + 0.5) / ss);
      Eigen::Vector2d n;
      if (!camera.undistort_point(px, &n)) n = Eigen::Vector2d(1e9, 1e9);
      rays_[static_cast<size_t>(y) * w + x] = n.cast<float>();
    }
}

double SyntheticRenderer::shade(double x, double y) const {
  const auto& o = target_.sheet_origin_m;
  if (x < o.x() || y < o.y() || x > o.x() + target_.sheet_width_m ||
      y > o.y() + target_.sheet_height_m)
    return o_.background_dn;
  for (const auto& m : target_.markers) {
    const double cell = m.side_m / vision::kMarkerCells;
    const double u = (x - m.centre_m.x() + m.side_m / 2) / cell;
    const double v = (y - m.centre_m.y() + m.side_m / 2) / cell;
    if (u >= 0 && v >= 0 && u < vision::kMarkerCells && v < vision::kMarkerCells)
      return vision::Codebook::marker_cell_is_white(codebook_.code(m.id), static_cast<int>(v),
                                                    static_cast<int>(u))
                 ? o_.paper_dn
                 : o_.ink_dn;
  }
  return o_.paper_dn;
}

cv::Mat SyntheticRenderer::render(const vision::Pose& T_cam_target, uint64_t seed,
                                  std::vector<std::array<Eigen::Vector2d, 4>>* truth) const {
  const int ss = o_.supersampling, W = camera_.width_px(), H = camera_.height_px();
  const Eigen::Matrix3d Rt = T_cam_target.R.transpose();
  const Eigen::Vector3d c = -(Rt * T_cam_target.t);  // camera centre in the target frame
  cv::Mat img(H, W, CV_32F);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      double sum = 0;
      for (int b = 0; b < ss; ++b)
        for (int a = 0; a < ss; ++a) {
          const Eigen::Vector2f n = rays_[static_cast<size_t>(y * ss + b) * W * ss + x * ss + a];
          const Eigen::Vector3d d = Rt * Eigen::Vector3d(n.x(), n.y(), 1);
          const double lambda = -c.z() / d.z();
          if (!(lambda > 0) || n.x() > 1e8) {
            sum += o_.background_dn;
            continue;
          }
          const Eigen::Vector3d p = c + lambda * d;
          sum += shade(p.x(), p.y());
        }
      img.at<float>(y, x) = static_cast<float>(sum / (ss * ss));
    }
  if (o_.blur_sigma_px > 0) cv::GaussianBlur(img, img, cv::Size(0, 0), o_.blur_sigma_px);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0, o_.noise_sigma_dn);
  cv::Mat out(H, W, CV_8U);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      out.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(img.at<float>(y, x) + noise(rng));
  if (truth) {
    truth->clear();
    for (const auto& m : target_.markers) {
      std::array<Eigen::Vector2d, 4> px;
      const auto corners = target_.corners_m(m);
      for (int k = 0; k < 4; ++k)
        px[k] = camera_.project(T_cam_target * corners[k]);
      truth->push_back(px);
    }
  }
  return out;
}

}  // namespace detector_test
