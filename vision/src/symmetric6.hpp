// Symmetric positive-definite 6x6 systems, stored by their lower triangle and
// solved through 3x3 blocks: the information matrices of the iterated EKF
// (vision/src/pose_ekf.cpp). Plain doubles at fixed offsets, so that the
// compiler keeps a whole solve in registers. Internal to the EKF.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <cstring>

namespace vision::detail {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

// Where entry (i, j), j <= i, of a symmetric 6x6 matrix is kept: row by row.
constexpr int lower_index(int i, int j) {
  return i * (i + 1) / 2 + j;
}

// A symmetric 6x6 matrix by its lower triangle (lower_index).
struct Symmetric6 {
  double lower[21];

  double operator()(int i, int j) const {
    return i >= j ? lower[lower_index(i, j)] : lower[lower_index(j, i)];
  }
  // The diagonal, in order.
  Vector6d diagonal() const {
    Vector6d d;
    for (int i = 0; i < 6; ++i)
      d(i) = lower[lower_index(i, i)];
    return d;
  }
  // True when every entry off the diagonal is exactly zero.
  bool is_diagonal() const {
    for (int i = 1; i < 6; ++i)
      for (int j = 0; j < i; ++j)
        if (lower[lower_index(i, j)] != 0) return false;
    return true;
  }
  // This matrix times v.
  Vector6d operator*(const Vector6d& v) const {
    Vector6d out;
    for (int i = 0; i < 6; ++i) {
      double sum = 0;
      for (int j = 0; j < 6; ++j)
        sum += (*this)(i, j) * v(j);
      out(i) = sum;
    }
    return out;
  }
};

// The lower triangle of a (symmetric) matrix; its upper one is not read.
inline Symmetric6 lower_triangle(const Matrix6d& m) {
  Symmetric6 s;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j <= i; ++j)
      s.lower[lower_index(i, j)] = m(i, j);
  return s;
}

inline Matrix6d full_matrix(const Symmetric6& s) {
  Matrix6d m;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      m(i, j) = s(i, j);
  return m;
}

// Entry (i, j) of a symmetric 3x3 matrix kept by its lower triangle.
inline double symmetric3(const double m[6], int i, int j) {
  return i >= j ? m[lower_index(i, j)] : m[lower_index(j, i)];
}

// The adjugate of a symmetric 3x3 matrix and its determinant, both from its
// lower triangle (m00, m10, m11, m20, m21, m22); the adjugate by its lower
// triangle too. The inverse is adj / det. False when the determinant is
// outside 1e-200..1e200 in magnitude (zero and not finite included): Spd6
// forms products as large as the determinant of its scaled Schur complement
// (below) before it divides, which must stay well inside double's normal
// range (1e-308..1e308) to keep their precision; the caller then solves
// another way.
struct Adjugate3 {
  double adj[6];
  double det;
};

inline bool adjugate3_symmetric(const double m[6], Adjugate3* out) {
  const double m00 = m[0], m10 = m[1], m11 = m[2], m20 = m[3], m21 = m[4], m22 = m[5];
  out->adj[0] = m11 * m22 - m21 * m21;
  out->adj[1] = m20 * m21 - m10 * m22;
  out->adj[2] = m00 * m22 - m20 * m20;
  out->adj[3] = m10 * m21 - m20 * m11;
  out->adj[4] = m10 * m20 - m00 * m21;
  out->adj[5] = m00 * m11 - m10 * m10;
  out->det = m00 * out->adj[0] + m10 * out->adj[1] + m20 * out->adj[3];
  return std::abs(out->det) >= 1e-200 && std::abs(out->det) <= 1e200;
}

// A symmetric positive-definite 6x6 system in 3x3 blocks (angles,
// translation), its diagonal multiplied by `diagonal_scale` (the
// Levenberg-Marquardt damping, 1 + lambda): A = [A11 A21^T; A21 A22],
// eliminated through the Schur complement S = A22 - A21 A11^-1 A21^T, both
// 3x3 inverses in closed form as adjugate over determinant. No pivoting (the
// blocks of a positive-definite matrix and its Schur complement are positive
// definite). With d = det(A11) and adj(A11) = d A11^-1, the elimination is
// carried scaled by d, so that no step waits for a division until the end:
// V = adj(A11) A21^T, S' = d S = d A22 - A21 V, and for b = (b1, b2)
//   y' = adj(A11) b1, r' = d b2 - A21 y', x2 = adj(S') r' / det(S'),
//   x1 = (y' - V x2) / d,
// the two reciprocals computed beside the products they scale. S' is of
// size s^4 for entries of size s and det(S') of size s^12, which
// adjugate3_symmetric's bounds keep inside double's range. `ok` is false when
// a block is singular to rounding or its scale is extreme; the caller then
// solves another way.
struct Spd6 {
  Adjugate3 a11, schur;  // of A11 and of S'
  double inv_det11 = 0, inv_det_schur = 0;
  double A21[3][3], V[3][3];  // V = adj(A11) A21^T
  bool ok = false;

  explicit Spd6(const Symmetric6& A, double diagonal_scale = 1.0) {
    const double* a = A.lower;
    const double A11[6] = {a[0] * diagonal_scale, a[1], a[2] * diagonal_scale, a[3], a[4],
                           a[5] * diagonal_scale};
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k)
        A21[i][k] = a[lower_index(3 + i, k)];
    if (!adjugate3_symmetric(A11, &a11)) return;
    inv_det11 = 1.0 / a11.det;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        V[i][j] = adj11(i, 0) * A21[j][0] + adj11(i, 1) * A21[j][1] + adj11(i, 2) * A21[j][2];
    double S[6];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j <= i; ++j)
        S[lower_index(i, j)] =
            a11.det * (a[lower_index(3 + i, 3 + j)] * (i == j ? diagonal_scale : 1.0)) -
            (A21[i][0] * V[0][j] + A21[i][1] * V[1][j] + A21[i][2] * V[2][j]);
    if (!adjugate3_symmetric(S, &schur)) return;
    inv_det_schur = 1.0 / schur.det;
    ok = true;
  }

  // A^-1 b (of the scaled A).
  Vector6d solve(const Vector6d& b) const {
    double y1[3], r[3], x2[3];
    for (int i = 0; i < 3; ++i)
      y1[i] = adj11(i, 0) * b(0) + adj11(i, 1) * b(1) + adj11(i, 2) * b(2);
    for (int i = 0; i < 3; ++i)
      r[i] = a11.det * b(3 + i) - (A21[i][0] * y1[0] + A21[i][1] * y1[1] + A21[i][2] * y1[2]);
    for (int i = 0; i < 3; ++i)
      x2[i] = (adj_schur(i, 0) * r[0] + adj_schur(i, 1) * r[1] + adj_schur(i, 2) * r[2]) *
              inv_det_schur;
    double x1[3];
    for (int i = 0; i < 3; ++i)
      x1[i] = (y1[i] - (V[i][0] * x2[0] + V[i][1] * x2[1] + V[i][2] * x2[2])) * inv_det11;
    // Stored as pairs, the way Eigen's vectorised expressions read a Vector6d
    // back, so that each read takes its pair straight from the store.
    typedef double Pair __attribute__((vector_size(16)));
    const Pair pairs[3] = {{x1[0], x1[1]}, {x1[2], x2[0]}, {x2[1], x2[2]}};
    Vector6d x;
    std::memcpy(x.data(), pairs, sizeof pairs);
    return x;
  }

 private:
  double adj11(int i, int j) const { return symmetric3(a11.adj, i, j); }
  double adj_schur(int i, int j) const { return symmetric3(schur.adj, i, j); }
};

// A^-1 b by Eigen's pivoting LDLT, for systems whose blocks Spd6 cannot
// invert. Rare: kept out of line, so that the loops calling solve_spd stay
// small.
[[gnu::noinline, gnu::cold]] inline Vector6d solve_spd_pivoting(const Symmetric6& A,
                                                                const Vector6d& b,
                                                                double diagonal_scale) {
  Matrix6d scaled = full_matrix(A);
  scaled.diagonal() *= diagonal_scale;
  return scaled.ldlt().solve(b);
}

// A^-1 b for the symmetric positive-definite A, its diagonal multiplied by
// `diagonal_scale` (Eigen's pivoting LDLT when a pivot fails).
inline Vector6d solve_spd(const Symmetric6& A, const Vector6d& b, double diagonal_scale = 1.0) {
  const Spd6 factors(A, diagonal_scale);
  if (factors.ok) return factors.solve(b);
  return solve_spd_pivoting(A, b, diagonal_scale);
}

// A^-1 of the symmetric positive-definite A, column by column.
inline Matrix6d inverse_spd(const Symmetric6& A) {
  const Spd6 factors(A);
  if (!factors.ok) return full_matrix(A).ldlt().solve(Matrix6d::Identity());
  Matrix6d inverse;
  for (int j = 0; j < 6; ++j)
    inverse.col(j) = factors.solve(Vector6d::Unit(j));
  return inverse;
}

}  // namespace vision::detail
