#include "vision/pose_opencv.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "square_frame.hpp"

namespace vision {
namespace {

Pose pose_from_cv(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat R_cv;
  cv::Rodrigues(rvec, R_cv);
  Pose T;
  cv::cv2eigen(R_cv, T.R);
  cv::cv2eigen(tvec, T.t);
  return T;
}

}  // namespace

std::string OpenCvSolver::name() const {
  switch (method_) {
    case Method::kIppeSquare:
      return "opencv_ippe_square";
    case Method::kIterative:
      return "opencv_iterative";
    case Method::kSqpnp:
      return "opencv_sqpnp";
  }
  return "opencv_unknown";
}

Estimate OpenCvSolver::solve_pose(const Correspondences& c, const SolverHint&) const {
  // OpenCV gets the pixels as they would be without distortion, undistorted
  // once by our camera model: cv::undistortPoints stops after a fixed five
  // iterations, which leaves up to 1e-4 px of error at this lens's corners and
  // would measure OpenCV's undistortion instead of its pose solvers.
  const cv::Mat K = c.camera->camera_matrix_cv();
  const cv::Mat no_distortion;
  const Intrinsics& k = c.camera->intrinsics();
  auto undistorted_px = [&](size_t i) {
    return cv::Point2d(k.fx * c.normalized[i].x() + k.cx, k.fy * c.normalized[i].y() + k.cy);
  };
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  Pose T_square_target;  // identity unless the square frame is used
  if (method_ == Method::kIppeSquare) {
    if (c.size() != 4 || !c.square_side_m)
      return unsolved(Termination::kNotApplicable,
                      "SOLVEPNP_IPPE_SQUARE needs exactly the four corners of a square");
    // OpenCV's fixed order: (-s/2, s/2), (s/2, s/2), (s/2, -s/2), (-s/2, -s/2),
    // which in our square frame (x along AB, y along AD) are D, C, B, A.
    const double h = *c.square_side_m / 2;
    object = {{-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}};
    for (size_t i : {3, 2, 1, 0})
      image.push_back(undistorted_px(i));
    T_square_target = detail::square_in_target(c).inverse();
  } else {
    for (size_t i = 0; i < c.size(); ++i) {
      const auto& P = c.object_points[i];
      object.emplace_back(P.x(), P.y(), P.z());
      image.push_back(undistorted_px(i));
    }
  }
  const int flag = method_ == Method::kIppeSquare  ? cv::SOLVEPNP_IPPE_SQUARE
                   : method_ == Method::kIterative ? cv::SOLVEPNP_ITERATIVE
                                                   : cv::SOLVEPNP_SQPNP;
  cv::Mat rvec, tvec;
  bool ok = false;
  try {
    ok = cv::solvePnP(object, image, K, no_distortion, rvec, tvec, false, flag);
  } catch (const cv::Exception& ex) {
    return unsolved(Termination::kNumericalFailure, std::string("solvePnP threw: ") + ex.what());
  }
  if (!ok || rvec.empty() || tvec.empty())
    return unsolved(Termination::kNumericalFailure, "solvePnP returned false");
  Estimate e;
  e.T_cam_target = pose_from_cv(rvec, tvec) * T_square_target;
  e.converged = true;
  e.termination = Termination::kConverged;
  return e;
}

}  // namespace vision
