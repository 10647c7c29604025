// A small, independent ray-casting renderer of a target sheet for the detector
// tests: per sub-pixel ray through the inverse lens model, ray-plane
// intersection, point lookup of the artwork, box average of ss x ss sub-pixels,
// Gaussian blur, Gaussian noise. Slower and simpler than sim::scene::SceneRenderer;
// it lets the detector's geometry be checked against a second, independent
// implementation of the image formation.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "vision/camera.hpp"
#include "vision/codebook.hpp"
#include "vision/pose.hpp"
#include "vision/target.hpp"

namespace detector_test {

struct SyntheticOptions {
  int supersampling = 4;  // sub-pixels per axis
  double paper_dn = 190;  // white paper, grey levels
  double ink_dn = 15;     // black toner
  double background_dn = 70;
  double blur_sigma_px = 0.6;
  double noise_sigma_dn = 1.5;
};

class SyntheticRenderer {
 public:
  // Precomputes one undistorted ray per sub-pixel of `camera`'s image.
  SyntheticRenderer(const vision::Camera& camera, const vision::Target& target,
                    const vision::Codebook& codebook, SyntheticOptions options = {});

  // Reflectance-like grey level at target point (x, y) metres.
  double shade(double x, double y) const;

  // An 8-bit image of the target seen at T_cam_target, noise drawn from
  // `seed`; `truth` (may be null) receives each marker's corners in pixels
  // (the camera's projection of the target's corners, marker by marker).
  cv::Mat render(const vision::Pose& T_cam_target, uint64_t seed,
                 std::vector<std::array<Eigen::Vector2d, 4>>* truth = nullptr) const;

 private:
  vision::Camera camera_;
  vision::Target target_;
  vision::Codebook codebook_;
  SyntheticOptions o_;
  std::vector<Eigen::Vector2f> rays_;
};

}  // namespace detector_test
