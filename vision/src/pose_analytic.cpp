#include "vision/pose_analytic.hpp"

#include <Eigen/LU>
#include <cmath>

#include "square_frame.hpp"

namespace vision {
namespace {

// The rotation nearest (Frobenius norm) to [u v u x v] for unit vectors u, v
// that are not parallel, in closed form: the same matrix nearest_rotation's
// SVD gives, without iterating. With e1, e2 the unit bisectors of u + v and
// u - v and n = (u x v) / |u x v|, [u v u x v] = [e1 e2 n] S with
// S = [a a 0; b -b 0; 0 0 |u x v|] (a = |u + v| / 2, b = |u - v| / 2); the
// polar factor of S is blockdiag([1 1; 1 -1] / sqrt 2, 1) up to the sign fixed
// by det = +1, so the nearest rotation's columns are (e1 + e2) / sqrt 2,
// (e1 - e2) / sqrt 2 and n: u and v turned symmetrically apart to 90 degrees.
Eigen::Matrix3d nearest_rotation_of_axes(const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
  const Eigen::Vector3d e1 = (u + v).normalized(), e2 = (u - v).normalized();
  Eigen::Matrix3d R;
  R.col(0) = (e1 + e2) * M_SQRT1_2;
  R.col(1) = (e1 - e2) * M_SQRT1_2;
  R.col(2) = u.cross(v).normalized();
  return R;
}

}  // namespace

bool analytic_square_pose(const Correspondences& c, Pose* T_cam_target, std::string* why) {
  if (!c.square_side_m) {
    *why = "the first four object points are not a square A, B, C, D";
    return false;
  }
  // Homogeneous normalized rays of A, B, C, D (z = 1).
  Eigen::Vector3d ray[4];
  for (int i = 0; i < 4; ++i)
    ray[i] = c.normalized[i].homogeneous();

  // Eq. 3: AB = DC, i.e. Z_A a - Z_B b + Z_C c - Z_D d = 0. With Z_A = 1:
  // [b  -c  d] (Z_B, Z_C, Z_D)^T = a, solved in closed form (eq. 4, Cramer's rule).
  Eigen::Matrix3d M;
  M.col(0) = ray[1];
  M.col(1) = -ray[2];
  M.col(2) = ray[3];
  const double det = M.determinant();
  if (!(std::abs(det) > 1e-12)) {
    *why = "the depth system of eq. 3 is singular (the square is seen edge-on or degenerate)";
    return false;
  }
  const Eigen::Vector3d depth_bcd = M.inverse() * ray[0];
  if (!(depth_bcd.minCoeff() > 0)) {
    *why = "a corner depth from eq. 4 is not positive (the quadrilateral is not a square's image)";
    return false;
  }
  Eigen::Vector3d P[4] = {ray[0], depth_bcd(0) * ray[1], depth_bcd(1) * ray[2],
                          depth_bcd(2) * ray[3]};

  // Scale from the known side: the reconstruction is a parallelogram up to
  // scale; its mean side length is set to the printed side.
  const double mean_side = 0.5 * ((P[1] - P[0]).norm() + (P[3] - P[0]).norm());
  const double scale = *c.square_side_m / mean_side;
  for (auto& p : P)
    p *= scale;

  // Eq. 5 (with its r1 read as AC + DB, see the header): the diagonals' sum and
  // difference are along the square's x and y axes.
  const Eigen::Vector3d ac = P[2] - P[0], db = P[1] - P[3];
  const Pose T_cam_square{nearest_rotation_of_axes((ac + db).normalized(), (ac - db).normalized()),
                          (P[0] + P[1] + P[2] + P[3]) / 4.0};
  *T_cam_target = T_cam_square * detail::square_in_target(c).inverse();
  return true;
}

Estimate AnalyticSolver::solve_pose(const Correspondences& c, const SolverHint&) const {
  if (c.size() != 4 || !c.square_side_m)
    return unsolved(Termination::kNotApplicable,
                    "analytic needs exactly the four corners of a square, got " +
                        std::to_string(c.size()) + " points" +
                        (c.square_side_m ? "" : " that are not a square A, B, C, D"));
  Estimate e;
  std::string why;
  if (!analytic_square_pose(c, &e.T_cam_target, &why))
    return unsolved(Termination::kDegenerate, why);
  e.converged = true;
  e.termination = Termination::kClosedForm;
  return e;
}

}  // namespace vision
