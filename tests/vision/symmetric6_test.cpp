// The EKF's 6x6 solves (vision/src/symmetric6.hpp: 3x3 blocks, their inverses
// as adjugate over determinant, Eigen's pivoting LDLT where those would not
// do) at every scale an information or covariance matrix can have. The
// block solve's products reach the twelfth power of the entries (the
// determinant of the Schur complement scaled by det(A11)), so without the
// scale bounds a matrix of entries 1e30 overflows, and at 1e-26 they fall
// below double's normal range; with them every scale solves as well as at
// scale 1.
#include "symmetric6.hpp"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <random>

namespace {

using vision::detail::inverse_spd;
using vision::detail::lower_triangle;
using vision::detail::Matrix6d;
using vision::detail::solve_spd;
using vision::detail::Vector6d;

// A random symmetric positive-definite matrix: a random rotation of the
// eigenvalues 1, 2, 4, ..., 32 (condition number 32), times `scale`.
Matrix6d random_spd(std::mt19937_64& rng, double scale) {
  std::normal_distribution<double> normal;
  Matrix6d B;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      B(i, j) = normal(rng);
  const Matrix6d Q = Eigen::HouseholderQR<Matrix6d>(B).householderQ();
  Vector6d eigenvalues;
  for (int i = 0; i < 6; ++i)
    eigenvalues(i) = std::ldexp(1.0, i);
  const Matrix6d A = Q * eigenvalues.asDiagonal() * Q.transpose() * scale;
  return 0.5 * (A + A.transpose());
}

// Scales 1e-120 to 1e120: the entries are normal doubles, so a pivoting LDLT
// solves each system as well as at scale 1, and the block solve must too,
// itself or by handing it to LDLT. The bound: a backward-stable solve of
// condition number 32 errs by about 32 x 1.1e-16 = 3.5e-15 relative; the
// block solve's closed-form inverses lose about the square of it, 32^2 x
// 1.1e-16 = 1.1e-13, and 1e-12 leaves ten times that (measured: at most
// 4.6e-15 a solve, 6.8e-15 an inverse). Without the bounds the solve returns
// NaN at every scale from 1e30 up (checked). 50
// matrices a scale, fixed seed.
TEST(Spd6, SolvesAndInvertsAtEveryScaleAsAtScaleOne) {
  std::mt19937_64 rng(17);
  std::normal_distribution<double> normal;
  for (int exponent = -120; exponent <= 120; exponent += 10) {
    const double scale = std::pow(10.0, exponent);
    for (int k = 0; k < 50; ++k) {
      const Matrix6d A = random_spd(rng, scale);
      Vector6d x;
      for (int i = 0; i < 6; ++i)
        x(i) = normal(rng);
      const Vector6d solved = solve_spd(lower_triangle(A), A * x);
      ASSERT_LT((solved - x).norm(), 1e-12 * x.norm()) << "scale 1e" << exponent;
      const Matrix6d inverse = inverse_spd(lower_triangle(A));
      ASSERT_LT((inverse * A - Matrix6d::Identity()).norm(), 1e-12) << "scale 1e" << exponent;
    }
  }
}

// The damping: the same system with its diagonal multiplied by 1 + lambda is
// the matrix A + lambda diag(A), whatever the scale.
TEST(Spd6, ScalesTheDiagonalAsTheDampingAsks) {
  std::mt19937_64 rng(23);
  std::normal_distribution<double> normal;
  for (double scale : {1e-60, 1.0, 1e60}) {
    for (double lambda : {1e-6, 1.0, 1e6}) {
      const Matrix6d A = random_spd(rng, scale);
      Matrix6d damped = A;
      damped.diagonal() *= 1.0 + lambda;
      Vector6d x;
      for (int i = 0; i < 6; ++i)
        x(i) = normal(rng);
      const Vector6d solved = solve_spd(lower_triangle(A), damped * x, 1.0 + lambda);
      // The eigenvalues of A + lambda D (D = diag(A), whose entries lie
      // between A's extreme eigenvalues 1 and 32 scaled) lie between
      // lambda_min(A) + lambda min(D) and lambda_max(A) + lambda max(D): the
      // condition number stays at most 32, and so does the bound above.
      EXPECT_LT((solved - x).norm(), 1e-12 * x.norm()) << scale << " " << lambda;
    }
  }
}

}  // namespace
