// The geometry stage of the renderer: the sheet's radiance seen through every
// pixel (private to sim_scene).
#pragma once

#include <opencv2/core.hpp>

#include "rays.hpp"
#include "sheet.hpp"
#include "sim/scene/renderer.hpp"

namespace sim::scene::detail {

// Adds weight x the radiance of each pixel (reflectance x illumination on the
// sheet, `background` (CV_32FC1, or empty for the uniform
// options.background_reflectance) where the sheet is not) into `radiance`
// (CV_32FC1). `front` is drawn when the printed side faces the camera, `back`
// otherwise. Area-correct: see sim/scene/renderer.hpp, steps 1-3.
void accumulate_radiance(const RayTable& rays, const SheetArtwork& front, const SheetArtwork& back,
                         const SceneOptions& options, const vision::Pose& T_cam_target,
                         const cv::Mat& background, float weight, cv::Mat& radiance);

}  // namespace sim::scene::detail
