// The EKF's measurement system (Maidi et al. 2010, eqs. 15-17 and 29): the
// residuals of the projected corners and their Jacobian with respect to the
// state (psi, theta, phi, tx, ty, tz), accumulated into H^T H and H^T r,
// four points at a time, and weighted into the update's system. Internal to
// vision::iterated_ekf (vision/include/vision/pose_ekf.hpp).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "cpu_builds.hpp"
#include "symmetric6.hpp"
#include "vision/correspondences.hpp"
#include "vision/pose_ekf.hpp"

namespace vision::detail {

// Four values, one per point of a block (GCC/Clang vector extension: element
// arithmetic, SSE2 pairs on baseline x86-64, one AVX register where the
// target has it). Aligned as a double, so that no allocator or stack frame
// has to provide 32 bytes (unaligned AVX loads cost nothing on aligned data).
typedef double Lanes __attribute__((vector_size(32), aligned(8)));

// The sines and cosines of a state's three Euler angles (psi, theta, phi),
// in the first three lanes (the fourth is not used): the update computes the
// three together.
struct EulerTrig {
  Lanes s, c;
};

// The correspondences in blocks of four points (structure of arrays): the
// layout the measurement reads. The last block is padded with copies of the
// last point at weight 0.
struct EkfPoints {
  struct Block {
    Lanes X, Y, Z;               // object point, target frame, metres
    Lanes nx, ny;                // observed undistorted normalised coordinates
    Lanes weight;                // 1 for a point, 0 for padding
    Lanes fx_weight, fy_weight;  // the focal lengths times the weight, pixels
  };
  std::vector<Block> blocks;
  std::size_t count = 0;  // points (the padding not counted)

  explicit EkfPoints(const Correspondences& c);
};

// The update's system at one state, which the measurement makes from its
// sums: the information I = P^-1 + R^-1 H^T H (per state unit^2) by its
// lower triangle and R^-1 H^T r (per state unit), where r = z - h(x) is the
// observed minus the predicted undistorted pixel of every point (|r|^2 is
// the projection's: EkfProjection). `unused` makes the 28 terms seven groups
// of four lanes, which the measurement stores 32 bytes at a time; it also
// puts H^T r on a 16-byte boundary, so that none of the pairs in which Eigen
// reads it back straddles two of those stores (a load that does waits for
// both to retire).
struct UpdateSystem {
  Symmetric6 information;
  double unused;
  double weighted_Htr[6];
};

// What turns the measurement's sums into the update's system, system = prior
// + inv_r sums: the prior's information P^-1 in UpdateSystem's layout (zero
// for H^T r and `unused`), as the seven groups of four lanes the measurement
// adds it to, and R^-1 = 1 / sigma^2, px^-2.
struct SystemWeights {
  Lanes prior[sizeof(UpdateSystem) / sizeof(Lanes)];
  double inv_r;

  SystemWeights(const Symmetric6& prior_information, double inv_r);
};

// The rotation R = Rz(psi) Ry(theta) Rx(phi) at a state, by the products of
// Ry Rx (m) and R (r) that the measurement uses, its translation and psi's
// sine and cosine.
struct Projection {
  double sz, cz;                                  // psi
  double m00, m01, m02, m11, m12, m20, m21, m22;  // Ry Rx (m10 = 0)
  double r01, r02, r11, r12, r21, r22;            // columns 1 and 2 of R
  double tx, ty, tz;                              // translation, m

  Projection() = default;
  Projection(const Vector6d& x, const EulerTrig& trig)
      : sz(trig.s[0]), cz(trig.c[0]), tx(x(3)), ty(x(4)), tz(x(5)) {
    const double sy = trig.s[1], cy = trig.c[1], sx = trig.s[2], cx = trig.c[2];
    m00 = cy;
    m01 = sy * sx;
    m02 = sy * cx;
    m11 = cx;
    m12 = -sx;
    m20 = -sy;
    m21 = cy * sx;
    m22 = cy * cx;
    r01 = cz * m01 - sz * m11;
    r02 = cz * m02 - sz * m12;
    r11 = sz * m01 + cz * m11;
    r12 = sz * m02 + cz * m12;
    r21 = m21;
    r22 = m22;
  }
  // R itself.
  Eigen::Matrix3d rotation() const {
    Eigen::Matrix3d R;
    R << cz * m00, r01, r02, sz * m00, r11, r12, m20, r21, r22;
    return R;
  }
};

// One block of points projected at a state: what the Jacobian is made of.
struct ProjectedBlock {
  Lanes Qx, Qz;    // Ry Rx P
  Lanes RPx, RPy;  // R P, its first two coordinates
  Lanes u, v;      // the projected normalised point
  Lanes ax, by;    // fx / z and fy / z (times the weight), pixels per metre
  Lanes e0, e1;    // observed minus predicted pixel (times the weight)
};

// The measurement at one state in two steps: project every point and sum the
// squared residuals (the cost needs no more), then, for a state the update
// keeps, the sums of its Jacobian. The caller owns `blocks`, one per block of
// the points.
struct EkfProjection {
  Projection pose;  // the state's rotation products and translation
  ProjectedBlock* blocks;
  double residual_squared;  // |r|^2, pixels^2
};

// Projects the points at state x (whose Euler sines and cosines are `trig`)
// into `out`. False, and `out` not usable, when a point is on or behind the
// camera (z <= 0).
using EkfProject = bool (*)(const EkfPoints& points, const Vector6d& x, const EulerTrig& trig,
                            EkfProjection* out);
// The update's system from the projection's Jacobian sums, weighted by `w`.
using EkfSystem = void (*)(const EkfPoints& points, const EkfProjection& projection,
                           const SystemWeights& w, UpdateSystem* system);
// The two steps, one pair per instruction set.
struct EkfMeasurement {
  EkfProject project;
  EkfSystem system;
};
EkfMeasurement ekf_measurement(EkfInstructionSet set);

// The set to run: `requested` where the CPU runs it, else the fastest it runs.
EkfInstructionSet ekf_instruction_set(std::optional<EkfInstructionSet> requested);

}  // namespace vision::detail
