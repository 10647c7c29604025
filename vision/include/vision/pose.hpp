// vision::Pose: a rigid transform between two frames.
//
// Naming follows the frame convention p_a = T_a_b * p_b: `T_cam_target` maps a
// point from the target frame (metres, origin at the target-frame origin, z
// normal to the sheet) to the camera frame (x right, y down, z forward).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vision {

struct Pose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // rotation, orthonormal, det +1
  Eigen::Vector3d t = Eigen::Vector3d::Zero();      // translation, metres

  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return R * p + t; }
  Pose operator*(const Pose& other) const { return {R * other.R, R * other.t + t}; }
  Pose inverse() const { return {R.transpose(), -(R.transpose() * t)}; }
  // Distance from the origin of the left frame to the origin of the right one, metres.
  double distance_m() const { return t.norm(); }
};

// Angle of the rotation R_a^T R_b, radians in [0, pi].
double rotation_angle_between(const Eigen::Matrix3d& R_a, const Eigen::Matrix3d& R_b);

// Rotation from Z-Y-X Euler angles, as the paper's EKF state (psi, theta, phi):
// R = Rz(psi) Ry(theta) Rx(phi). Radians.
Eigen::Matrix3d rotation_from_euler_zyx(double psi, double theta, double phi);
// The inverse of rotation_from_euler_zyx, with theta in [-pi/2, pi/2].
Eigen::Vector3d euler_zyx_from_rotation(const Eigen::Matrix3d& R);

// Nearest rotation (Frobenius norm) to an arbitrary 3x3 matrix, via SVD with
// det fixed to +1.
Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& M);

}  // namespace vision
