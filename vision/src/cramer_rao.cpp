#include "vision/cramer_rao.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <string>

namespace vision {

PoseCovariance cramer_rao_bound(const PoseJacobian& jacobian, double sigma) {
  constexpr const char* kName = "cramer_rao_bound";
  if (!(sigma > 0.0) || !std::isfinite(sigma)) {
    throw CramerRaoError(std::string(kName) + ": sigma = " + std::to_string(sigma) +
                         " px; expected a finite noise level > 0");
  }
  if (jacobian.rows() < 6 || !jacobian.allFinite()) {
    throw CramerRaoError(std::string(kName) + ": a " + std::to_string(jacobian.rows()) +
                         " x 6 Jacobian; expected at least 6 rows of finite entries");
  }
  const Eigen::ColPivHouseholderQR<PoseJacobian> qr(jacobian);
  if (qr.rank() < 6) {
    throw CramerRaoError(std::string(kName) + ": the Jacobian has rank " +
                         std::to_string(qr.rank()) +
                         "; expected rank 6 (every pose parameter observable)");
  }
  // J P = Q R  =>  (J^T J)^-1 = P R^-1 R^-T P^T.
  const PoseCovariance r = qr.matrixR().topLeftCorner<6, 6>().triangularView<Eigen::Upper>();
  const PoseCovariance r_inv = r.triangularView<Eigen::Upper>().solve(PoseCovariance::Identity());
  const PoseCovariance p = qr.colsPermutation();
  return sigma * sigma * (p * (r_inv * r_inv.transpose()) * p.transpose());
}

double cramer_rao_bound(const PoseCovariance& bound, const PoseGradient& gradient) {
  return gradient.dot(bound * gradient);
}

}  // namespace vision
