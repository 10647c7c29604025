#include "vision/pose.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace vision {

double rotation_angle_between(const Eigen::Matrix3d& R_a, const Eigen::Matrix3d& R_b) {
  // ||R_a - R_b||_F = 2 sqrt(2) sin(angle / 2): unlike acos of the trace, this
  // keeps full precision for small angles, which the 1e-6 rad tests need.
  const double s = (R_a - R_b).norm() / (2.0 * std::sqrt(2.0));
  return 2.0 * std::asin(std::clamp(s, 0.0, 1.0));
}

Eigen::Matrix3d rotation_from_euler_zyx(double psi, double theta, double phi) {
  return (Eigen::AngleAxisd(psi, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d euler_zyx_from_rotation(const Eigen::Matrix3d& R) {
  // R = Rz(psi) Ry(theta) Rx(phi): R(2,0) = -sin(theta).
  const double theta = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  const double psi = std::atan2(R(1, 0), R(0, 0));
  const double phi = std::atan2(R(2, 1), R(2, 2));
  return {psi, theta, phi};
}

Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& M) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

}  // namespace vision
