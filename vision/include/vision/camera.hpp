// vision::Camera: the pinhole camera with Brown-Conrady lens distortion and
// thin-prism terms.
//
// Frames and units. A point p_cam (metres) in the camera frame (x right, y down,
// z forward along the optical axis) projects to the normalized image point
// (x, y) = (X/Z, Y/Z), is distorted (k1, k2, k3 radial; p1, p2 tangential, the
// OpenCV / Brown-Conrady "plumb bob" model; s1..s4 thin prism, Weng, Cohen &
// Herniou, "Camera calibration with distortion models and accuracy
// evaluation", IEEE PAMI 14(10), 1992, as OpenCV's CALIB_THIN_PRISM_MODEL),
// and mapped to pixels by the intrinsics. Pixels follow OpenCV's convention:
// the centre of the top-left pixel is (0, 0).
//
//   r2 = x^2 + y^2,  radial = 1 + k1 r2 + k2 r2^2 + k3 r2^3
//   xd = x radial + 2 p1 x y + p2 (r2 + 2 x^2) + s1 r2 + s2 r2^2
//   yd = y radial + p1 (r2 + 2 y^2) + 2 p2 x y + s3 r2 + s4 r2^2
//   u  = fx xd + cx,  v = fy yd + cy
//
// This is cv::projectPoints with the 12 coefficients (k1 k2 p1 p2 k3 k4 k5 k6
// s1 s2 s3 s4) and the rational terms k4 = k5 = k6 = 0: OpenCV's rational
// model is not represented (a calibration file with non-zero k4..k6 is
// refused), nor is its sensor tilt (tau_x, tau_y of 14 coefficients).
//
// The pose solvers work on undistorted normalized points; distortion is handled
// here, once (see vision/correspondences.hpp).
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace vision {

// A calibration file that cannot be read, lacks a key or holds a malformed
// value. The message names the file and the key.
class CalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Intrinsics {
  double fx = 0;  // focal length along u, pixels
  double fy = 0;  // focal length along v, pixels
  double cx = 0;  // principal point u, pixels
  double cy = 0;  // principal point v, pixels
};

// Brown-Conrady coefficients in OpenCV's order (k1, k2, p1, p2, k3), then the
// thin-prism coefficients s1..s4 (OpenCV's coefficients 9-12); dimensionless.
struct Distortion {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
  double s1 = 0, s2 = 0, s3 = 0, s4 = 0;
  bool has_thin_prism() const { return s1 != 0 || s2 != 0 || s3 != 0 || s4 != 0; }
};

class Camera {
 public:
  // Preconditions: fx, fy > 0, width, height > 0 and every value finite;
  // otherwise std::invalid_argument naming the value.
  Camera(const Intrinsics& intrinsics, const Distortion& distortion, int width_px, int height_px);

  // The reference paper's Sony XC-555 (Maidi et al. 2010, Table 1): 736x571,
  // fx 706.1, fy 731.1, cx 388.0, cy 269.6, k1 -0.2279, k2 0.1479,
  // p1 -0.0007985, p2 0.0006245, k3 0.
  static Camera paper_default();

  // Loads a calibration file, detecting the format by its content:
  //  - OpenCV FileStorage (YAML or XML, as written by calibrateCamera tools):
  //    `camera_matrix` (3x3), `distortion_coefficients` in OpenCV's order
  //    (4, 5, 8, 12 or 14 values: k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4
  //    [tau_x tau_y]]]]; the rational k4..k6 and the tilt tau must be zero),
  //    `image_width`, `image_height`;
  //  - ROS camera_info YAML: `image_width`, `image_height`,
  //    `camera_matrix: {rows, cols, data}`, `distortion_model: plumb_bob` (5
  //    values) or `rational_polynomial` (8 or 12 values, the order above),
  //    `distortion_coefficients: {rows, cols, data}`.
  // Throws CalibrationError naming the file and the key on a missing file, a
  // missing key, a malformed matrix or an unsupported distortion model, and
  // naming the file (and line) before OpenCV parses it when it is not a
  // regular file, is larger than 1 MiB or nests more than 32 levels deep
  // (OpenCV's parsers recurse once per level).
  static Camera load(const std::string& path);

  // Writes the calibration as an OpenCV FileStorage file (.yaml, .yml or .xml):
  // 5 distortion coefficients, or 12 (k4..k6 = 0) when it has a thin prism.
  void save(const std::string& path) const;

  const Intrinsics& intrinsics() const { return intrinsics_; }
  const Distortion& distortion() const { return distortion_; }
  int width_px() const { return width_px_; }
  int height_px() const { return height_px_; }
  bool has_distortion() const;

  // Whether an image of `image_size` pixels is the size this calibration was
  // made at (width_px() x height_px()): the intrinsics hold at no other size.
  // Returns nothing when it is; otherwise why not, naming both as the caller
  // names them: "CALIBRATION is for 736x571 px but IMAGE is 640x480 px"
  // (e.g. calibration "/abs/cam.yaml", image "image 'frame.png'").
  std::optional<std::string> image_size_mismatch(const cv::Size& image_size,
                                                 const std::string& image,
                                                 const std::string& calibration) const;

  // K as a 3x3 matrix (pixels).
  Eigen::Matrix3d K() const;
  // The same model as OpenCV expects it: 3x3 CV_64F and 1x5 CV_64F, or 1x12
  // (k1 k2 p1 p2 k3 0 0 0 s1 s2 s3 s4) when it has a thin prism.
  cv::Mat camera_matrix_cv() const;
  cv::Mat distortion_cv() const;

  // Projects a camera-frame point (metres) to distorted pixels. Precondition:
  // p_cam.z() > 0 (a point on or behind the camera plane yields non-finite or
  // mirrored pixels; callers check cheirality).
  Eigen::Vector2d project(const Eigen::Vector3d& p_cam) const;

  // Distorts an undistorted normalized point (x, y) = (X/Z, Y/Z) to pixels.
  Eigen::Vector2d distort_normalized(const Eigen::Vector2d& xy) const;

  // d(pixel)/d(normalized point) of distort_normalized at xy, 2x2.
  Eigen::Matrix2d distort_jacobian(const Eigen::Vector2d& xy) const;

  // Inverts the lens model: from an observed (distorted) pixel to the
  // undistorted normalized point whose projection is that pixel. Newton's
  // method on the 2x2 distortion Jacobian, run to the rounding floor and
  // accepted when the re-distorted point is within 1e-9 px of the input.
  // Returns false (and leaves xy NaN) when no such point exists on the lens's
  // own branch (the one containing the centre, before the polynomial folds
  // back; the thin prism, a shift of at most |s| r2 (1 + r2), is left out of
  // that test): outside the region where the model is invertible, which for real
  // lenses lies far beyond the image.
  bool undistort_point(const Eigen::Vector2d& pixel, Eigen::Vector2d* xy) const;

  // undistort_point over many pixels; a point that does not converge is NaN.
  std::vector<Eigen::Vector2d> undistort_points(const std::vector<Eigen::Vector2d>& pixels) const;

  // Tolerance of undistort_point, in pixels on the image.
  static constexpr double kUndistortTolerancePx = 1e-9;

 private:
  Intrinsics intrinsics_;
  Distortion distortion_;
  int width_px_;
  int height_px_;
};

}  // namespace vision
