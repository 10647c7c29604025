// Cramér-Rao lower bound for a pose estimate (the report's "efficiency"):
// with N corners measured in pixels under independent isotropic Gaussian noise
// of standard deviation sigma, and J the 2N x 6 Jacobian of the reprojected
// corners with respect to the 6 pose parameters at the true pose, the
// covariance of any unbiased pose estimator is at least
//     C = sigma^2 (J^T J)^-1
// (the inverse Fisher information of the Gaussian model; e.g. Kay,
// Fundamentals of Statistical Signal Processing: Estimation Theory, 1993,
// ch. 3). A solver's efficiency is its observed variance over the bound.
//
// Units: J in px per unit of each parameter (rad for rotation parameters, m
// for translation, in whatever order the caller's parameterisation uses);
// sigma in px; C in the parameters' units squared.
#pragma once

#include <Eigen/Core>
#include <stdexcept>

namespace vision {

// The bound was asked of a Jacobian or a noise level it is not defined for;
// the message names the input and what was expected.
class CramerRaoError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

using PoseJacobian = Eigen::Matrix<double, Eigen::Dynamic, 6>;
using PoseCovariance = Eigen::Matrix<double, 6, 6>;
using PoseGradient = Eigen::Matrix<double, 6, 1>;

// sigma^2 (J^T J)^-1, computed from a column-pivoted QR of J (never forming
// J^T J, whose condition number is the square of J's).
// Preconditions: J has at least 6 rows, finite entries and rank 6 (the pose is
// observable); sigma > 0 and finite. Throws CramerRaoError otherwise.
PoseCovariance cramer_rao_bound(const PoseJacobian& jacobian, double sigma);

// Lower bound on the variance of a scalar function f(pose) (e.g. the
// camera-target distance): g^T C g with g = df/dpose at the true pose (first
// order, exact for linear f). Units: those of f squared.
double cramer_rao_bound(const PoseCovariance& bound, const PoseGradient& gradient);

}  // namespace vision
