// The EKF's measurement system (Maidi et al. 2010, eqs. 15-17 and 29): the
// residuals of the projected corners and their Jacobian with respect to the
// state (psi, theta, phi, tx, ty, tz), accumulated into H^T H and H^T r,
// four points at a time. Internal to vision::iterated_ekf
// (vision/include/vision/pose_ekf.hpp).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "cpu_builds.hpp"
#include "symmetric6.hpp"
#include "vision/correspondences.hpp"
#include "vision/pose_ekf.hpp"

namespace vision::detail {

// The sines and cosines of a state's three Euler angles (psi, theta, phi).
struct EulerTrig {
  double s[3], c[3];
};

// Four values, one per point of a block (GCC/Clang vector extension: element
// arithmetic, SSE2 pairs on baseline x86-64, one AVX register where the
// target has it). Aligned as a double, so that no allocator or stack frame
// has to provide 32 bytes (unaligned AVX loads cost nothing on aligned data).
typedef double Lanes __attribute__((vector_size(32), aligned(8)));

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

// The sums the update takes from the measurement at one state, in the order
// the measurement accumulates them: H^T H (pixels^2 per state unit^2) by its
// lower triangle, H^T r, and |r|^2 (pixels^2), where r = z - h(x) is the
// observed minus the predicted undistorted pixel of every point.
struct MeasurementSums {
  Symmetric6 HtH;
  double Htr[6];
  double residual_squared;
};

// The measurement at state x (whose Euler sines and cosines are `trig`).
// False, and nothing written, when a point is on or behind the camera
// (z <= 0). One function per instruction set.
using EkfMeasurement = bool (*)(const EkfPoints& points, const Vector6d& x, const EulerTrig& trig,
                                MeasurementSums* sums);
EkfMeasurement ekf_measurement(EkfInstructionSet set);

// The set to run: `requested` where the CPU runs it, else the fastest it runs.
EkfInstructionSet ekf_instruction_set(std::optional<EkfInstructionSet> requested);

}  // namespace vision::detail
