#include "vision/pose_ippe.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>

#include "homography.hpp"

namespace vision {
namespace {

// Collins & Bartoli §3 (Algorithm 1, eqs. 16-18): the two rotations of a plane
// whose homography has Jacobian J at a point imaged at the normalized point v.
// Rv turns the z axis onto the ray through v; B = [I2 | -v] Rv[:, 0:2];
// A = B^-1 J has largest singular value gamma; R~ = A / gamma is completed to
// the first two columns of a rotation with a third row (b0, +-b1), the sign
// making the columns orthogonal; the two solutions differ in the sign of that
// row. R = Rv [c1 c2 c1 x c2].
std::array<Eigen::Matrix3d, 2> ippe_rotations(const Eigen::Matrix2d& J, const Eigen::Vector2d& v) {
  const Eigen::Vector3d ray = v.homogeneous().normalized();
  Eigen::Matrix3d Rv = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d axis = Eigen::Vector3d::UnitZ().cross(ray);
  if (axis.norm() > 1e-15)
    Rv = Eigen::AngleAxisd(std::acos(std::clamp(ray.z(), -1.0, 1.0)), axis.normalized())
             .toRotationMatrix();
  Eigen::Matrix2d B;
  B.row(0) = Rv.block<1, 2>(0, 0) - v.x() * Rv.block<1, 2>(2, 0);
  B.row(1) = Rv.block<1, 2>(1, 0) - v.y() * Rv.block<1, 2>(2, 0);
  const Eigen::Matrix2d A = B.inverse() * J;
  const Eigen::Matrix2d AtA = A.transpose() * A;
  const double gamma =
      std::sqrt(0.5 * (AtA.trace() + std::sqrt((AtA(0, 0) - AtA(1, 1)) * (AtA(0, 0) - AtA(1, 1)) +
                                               4.0 * AtA(0, 1) * AtA(0, 1))));
  const Eigen::Matrix2d Rt = A / gamma;
  const double b0 = std::sqrt(std::max(0.0, 1.0 - Rt.col(0).squaredNorm()));
  double b1 = std::sqrt(std::max(0.0, 1.0 - Rt.col(1).squaredNorm()));
  if (Rt.col(0).dot(Rt.col(1)) > 0) b1 = -b1;  // c1 . c2 = R~1.R~2 + b0 b1 = 0
  std::array<Eigen::Matrix3d, 2> out;
  for (int k = 0; k < 2; ++k) {
    const double s = k == 0 ? 1.0 : -1.0;
    Eigen::Matrix3d R;
    R.col(0) << Rt(0, 0), Rt(1, 0), s * b0;
    R.col(1) << Rt(0, 1), Rt(1, 1), s * b1;
    R.col(2) = R.col(0).cross(R.col(1));
    out[k] = Rv * R;
  }
  return out;
}

// Collins & Bartoli §4 (eq. 34): for a rotation R of the plane, the
// translation minimising the linearised image error sum_i ||x_i (r3.P_i + tz)
// - (r12.P_i + txy)||^2, a 3x3 linear least-squares problem.
Eigen::Vector3d ippe_translation(const Eigen::Matrix3d& R, const std::vector<Eigen::Vector2d>& P,
                                 const std::vector<Eigen::Vector2d>& x) {
  Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
  Eigen::Vector3d Atb = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < P.size(); ++i) {
    const Eigen::Vector3d RP = R.leftCols<2>() * P[i];
    const Eigen::Vector3d ru(1, 0, -x[i].x()), rv(0, 1, -x[i].y());
    AtA += ru * ru.transpose() + rv * rv.transpose();
    Atb += ru * (x[i].x() * RP.z() - RP.x()) + rv * (x[i].y() * RP.z() - RP.y());
  }
  return AtA.ldlt().solve(Atb);
}

}  // namespace

bool ippe_solutions(const Correspondences& c, std::array<Pose, 2>* T_cam_target,
                    std::array<double, 2>* reprojection_rms_px) {
  // Work about the centroid of the plane points, where the first-order
  // (infinitesimal) model is best conditioned (Collins & Bartoli §3.3).
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const auto& p : c.plane_points)
    centroid += p;
  centroid /= static_cast<double>(c.size());
  std::vector<Eigen::Vector2d> P(c.size());
  for (size_t i = 0; i < c.size(); ++i)
    P[i] = c.plane_points[i] - centroid;

  Eigen::Matrix3d H;
  if (!detail::plane_homography(P, c.normalized, &H)) return false;
  // v: image of the plane origin; J: Jacobian of the homography there.
  const Eigen::Vector2d v(H(0, 2), H(1, 2));
  Eigen::Matrix2d J;
  J << H(0, 0) - H(2, 0) * v.x(), H(0, 1) - H(2, 1) * v.x(), H(1, 0) - H(2, 0) * v.y(),
      H(1, 1) - H(2, 1) * v.y();
  if (!J.allFinite() || !(std::abs(J.determinant()) > 0)) return false;

  // Plane frame (centred) -> target frame.
  const Pose T_centred_plane{Eigen::Matrix3d::Identity(),
                             Eigen::Vector3d(-centroid.x(), -centroid.y(), 0)};
  const Pose T_centred_target = T_centred_plane * c.T_target_plane.inverse();
  const auto rotations = ippe_rotations(J, v);
  for (int k = 0; k < 2; ++k) {
    const Pose T_cam_plane{rotations[k], ippe_translation(rotations[k], P, c.normalized)};
    (*T_cam_target)[k] = T_cam_plane * T_centred_target;
    (*reprojection_rms_px)[k] = vision::reprojection_rms_px(c, (*T_cam_target)[k]);
  }
  if ((*reprojection_rms_px)[1] < (*reprojection_rms_px)[0]) {
    std::swap((*T_cam_target)[0], (*T_cam_target)[1]);
    std::swap((*reprojection_rms_px)[0], (*reprojection_rms_px)[1]);
  }
  return true;
}

Estimate IppeSolver::solve_pose(const Correspondences& c, const SolverHint&) const {
  std::array<Pose, 2> poses;
  std::array<double, 2> rms;
  if (!ippe_solutions(c, &poses, &rms))
    return unsolved(Termination::kDegenerate, "the plane-to-image homography is degenerate");
  Estimate e;
  e.T_cam_target = poses[0];
  e.converged = true;
  e.termination = Termination::kClosedForm;
  // Both errors zero (noise-free and unambiguous) count as fully ambiguous-free.
  e.ambiguity_ratio = rms[1] > 0 ? rms[0] / rms[1] : 0.0;
  return e;
}

}  // namespace vision
