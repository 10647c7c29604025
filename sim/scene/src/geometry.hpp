// The geometry stage of the renderer: the sheet's radiance seen through every
// pixel (private to sim_scene).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <opencv2/core.hpp>

#include "rays.hpp"
#include "sheet.hpp"
#include "sim/scene/renderer.hpp"

namespace sim::scene::detail {

// The bow of the sheet (SceneOptions::bow_sag_m): h(X, Y) metres towards the
// camera, clamped at 0 beyond the paraboloid's rim.
class SheetBow {
 public:
  SheetBow(const SceneOptions& options, const vision::Target& target);
  bool on() const { return sag_ != 0; }
  double operator()(double x_m, double y_m) const {
    if (sag_ == 0) return 0;
    const double u = x_m - cx_, v = y_m - cy_;
    return std::max(0.0, sag_ * (1 - ax_ * u * u - ay_ * v * v));
  }
  // The point of the bowed sheet above (X, Y) of the plane, target frame.
  Eigen::Vector3d surface(const Eigen::Vector3d& p) const {
    return Eigen::Vector3d(p.x(), p.y(), p.z() - (*this)(p.x(), p.y()));
  }

 private:
  double sag_ = 0, cx_ = 0, cy_ = 0, ax_ = 0, ay_ = 0;  // ax = wx / (W / 2)^2
};

// Adds weight x the radiance of each pixel (reflectance x illumination on the
// sheet, `background` (CV_32FC1, or empty for the uniform
// options.background_reflectance) where the sheet is not) into `radiance`
// (CV_32FC1). `front` is drawn when the printed side faces the camera, `back`
// otherwise. Area-correct: see sim/scene/renderer.hpp, steps 1-3.
// The bowed sheet (`bow`) is met by each ray a few fixed-point steps from
// its plane; the glare (SceneOptions::glare_peak) is added on the sheet.
void accumulate_radiance(const RayTable& rays, const SheetArtwork& front, const SheetArtwork& back,
                         const SceneOptions& options, const SheetBow& bow,
                         const vision::Pose& T_cam_target, const cv::Mat& background, float weight,
                         cv::Mat& radiance);

}  // namespace sim::scene::detail
