#include "homography.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>

namespace vision::detail {
namespace {

// Similarity that moves the points' centroid to the origin and their mean
// distance from it to sqrt(2) (Hartley normalisation).
Eigen::Matrix3d normaliser(const std::vector<Eigen::Vector2d>& pts) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : pts)
    mean += p;
  mean /= static_cast<double>(pts.size());
  double spread = 0;
  for (const auto& p : pts)
    spread += (p - mean).norm();
  spread /= static_cast<double>(pts.size());
  const double s = spread > 0 ? std::sqrt(2.0) / spread : 1.0;
  Eigen::Matrix3d N;
  N << s, 0, -s * mean.x(), 0, s, -s * mean.y(), 0, 0, 1;
  return N;
}

}  // namespace

bool plane_homography(const std::vector<Eigen::Vector2d>& plane,
                      const std::vector<Eigen::Vector2d>& image, Eigen::Matrix3d* H) {
  const Eigen::Matrix3d Np = normaliser(plane), Ni = normaliser(image);
  // Two rows per point of A h = b with h = (h11 h12 h13 h21 h22 h23 h31 h32), h33 = 1.
  using Vector8d = Eigen::Matrix<double, 8, 1>;
  using Matrix8d = Eigen::Matrix<double, 8, 8>;
  Matrix8d AtA = Matrix8d::Zero();
  Vector8d Atb = Vector8d::Zero();
  for (size_t i = 0; i < plane.size(); ++i) {
    const Eigen::Vector3d X = Np * plane[i].homogeneous();
    const Eigen::Vector3d x = Ni * image[i].homogeneous();
    Vector8d ru, rv;
    ru << X.x(), X.y(), 1, 0, 0, 0, -x.x() * X.x(), -x.x() * X.y();
    rv << 0, 0, 0, X.x(), X.y(), 1, -x.y() * X.x(), -x.y() * X.y();
    AtA += ru * ru.transpose() + rv * rv.transpose();
    Atb += ru * x.x() + rv * x.y();
  }
  const Eigen::LDLT<Matrix8d> ldlt(AtA);
  if (ldlt.info() != Eigen::Success ||
      !(ldlt.vectorD().cwiseAbs().minCoeff() > 1e-12 * ldlt.vectorD().cwiseAbs().maxCoeff()))
    return false;
  const Vector8d h = ldlt.solve(Atb);
  Eigen::Matrix3d Hn;
  Hn << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), 1.0;
  *H = Ni.inverse() * Hn * Np;
  if (!H->allFinite() || std::abs((*H)(2, 2)) < 1e-300) return false;
  *H /= (*H)(2, 2);
  return true;
}

}  // namespace vision::detail
