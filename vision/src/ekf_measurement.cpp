#include "ekf_measurement.hpp"

#include <cstddef>
#include <cstring>

namespace vision::detail {
namespace {

// The element-wise comparison result of two Lanes: -1 (all bits) or 0.
typedef long long LaneMask __attribute__((vector_size(32), aligned(8)));

// The sums of the lanes of a, b, c and d, as the four lanes of *sums:
// pairwise sums by shuffles, seven vector operations for four sums. (Vectors
// pass by reference: by value, their calling convention would depend on the
// instruction set.)
inline void sums_of(const Lanes& a, const Lanes& b, const Lanes& c, const Lanes& d, Lanes* sums) {
  const Lanes ab =
      __builtin_shufflevector(a, b, 0, 4, 2, 6) + __builtin_shufflevector(a, b, 1, 5, 3, 7);
  const Lanes cd =
      __builtin_shufflevector(c, d, 0, 4, 2, 6) + __builtin_shufflevector(c, d, 1, 5, 3, 7);
  *sums = __builtin_shufflevector(ab, cd, 0, 1, 4, 5) + __builtin_shufflevector(ab, cd, 2, 3, 6, 7);
}

}  // namespace

EkfPoints::EkfPoints(const Correspondences& c) : count(c.size()) {
  const double fx = c.camera->intrinsics().fx, fy = c.camera->intrinsics().fy;
  const size_t n = count;
  blocks.resize((n + 3) / 4);
  for (size_t b = 0; b < blocks.size(); ++b) {
    Block& block = blocks[b];
    for (size_t lane = 0; lane < 4; ++lane) {
      const size_t i = 4 * b + lane < n ? 4 * b + lane : n - 1;
      block.X[lane] = c.object_points[i].x();
      block.Y[lane] = c.object_points[i].y();
      block.Z[lane] = c.object_points[i].z();
      block.nx[lane] = c.normalized[i].x();
      block.ny[lane] = c.normalized[i].y();
      block.weight[lane] = 4 * b + lane < n ? 1.0 : 0.0;
      block.fx_weight[lane] = fx * block.weight[lane];
      block.fy_weight[lane] = fy * block.weight[lane];
    }
  }
}

namespace {

// The 28 sums that make H^T H (lower triangle, row by row, as lower_index
// keeps it), H^T r and a zero: the layout of UpdateSystem, so that the sums
// over the lanes, four at a time, are stored as they come. H^T H's (ty, tx)
// entry is zero (a point's x row has no ty term, its y row no tx term).
// clang-format off
enum Term {
  kRR00,                          // rotation block (psi, theta, phi)
  kRR10, kRR11,
  kRR20, kRR21, kRR22,
  kTX0, kTX1, kTX2, kTT00,        // translation rows x rotation columns; translation block
  kTY0, kTY1, kTY2, kTT10, kTT11,
  kTZ0, kTZ1, kTZ2, kTT20, kTT21, kTT22,
  kUnused,                        // UpdateSystem::unused, always 0
  kG0, kG1, kG2, kG3, kG4, kG5,   // gradient H^T r
  kTerms
};
// clang-format on
static_assert(kTerms % 4 == 0 && kTerms * sizeof(double) == sizeof(UpdateSystem),
              "the terms are UpdateSystem, in four-lane groups");
static_assert(kTT22 == lower_index(5, 5) && kG0 == 22, "H^T H first, by lower_index");
static_assert(offsetof(UpdateSystem, weighted_Htr) == kG0 * sizeof(double) && kG0 % 2 == 0,
              "H^T r where the terms put it, on a 16-byte boundary");

// One block projected by the state's rotation and translation r: its
// projected points and residuals, and their squares lane by lane into
// *residual; false when a point of it is on or behind the camera.
inline bool project_block(const EkfPoints::Block& p, const Projection& r, ProjectedBlock* q,
                          Lanes* residual) {
  q->Qx = r.m00 * p.X + r.m01 * p.Y + r.m02 * p.Z;
  const Lanes Qy = r.m11 * p.Y + r.m12 * p.Z;
  q->Qz = r.m20 * p.X + r.m21 * p.Y + r.m22 * p.Z;
  q->RPx = r.cz * q->Qx - r.sz * Qy;
  q->RPy = r.sz * q->Qx + r.cz * Qy;
  const Lanes pz = q->Qz + r.tz;
  const LaneMask in_front = (pz > 0) | (p.weight == 0);
  if (!(in_front[0] && in_front[1] && in_front[2] && in_front[3])) return false;
  const Lanes inv_z = 1.0 / pz;
  q->u = (q->RPx + r.tx) * inv_z;
  q->v = (q->RPy + r.ty) * inv_z;
  // Observed minus predicted pixel; padding lanes weigh nothing.
  q->ax = inv_z * p.fx_weight;
  q->by = inv_z * p.fy_weight;
  q->e0 = (p.nx - q->u) * p.fx_weight;
  q->e1 = (p.ny - q->v) * p.fy_weight;
  *residual = q->e0 * q->e0 + q->e1 * q->e1;
  return true;
}

// One projected block's terms, summed over its lanes four terms at a time in
// Term's order, into sums[kTerms / 4]. Each group of four is reduced as soon
// as it is made, so that a few vectors are live rather than 28 (AVX2 has 16
// registers): spilling and reloading all 28 made a 4-point solve ~4 % and a
// 16-point one ~10 % slower (bench_solvers, ABBA). With Q = Ry Rx P:
// dR/dpsi P = e_z x (R P) = (-(RP)_y, (RP)_x, 0), dR/dtheta P = Rz (e_y x Q)
// = (cos psi Q_z, sin psi Q_z, -Q_x), dR/dphi P = R (e_x x P) = R (0, -P_z,
// P_y). The two rows of dh/dp are fx/z (1, 0, -u) and fy/z (0, 1, -v) (u, v
// the projected point), so the translation columns of H are those rows
// themselves, and every entry of H^T H that involves them is a rotation
// column scaled by fx/z or fy/z, or a sum of squares.
inline void block_sums(const EkfPoints::Block& p, const Projection& r, const ProjectedBlock& q,
                       Lanes sums[kTerms / 4]) {
  const Lanes &ax = q.ax, &by = q.by, &u = q.u, &v = q.v, &e0 = q.e0, &e1 = q.e1;
  const Lanes dphi_x = r.r02 * p.Y - r.r01 * p.Z, dphi_y = r.r12 * p.Y - r.r11 * p.Z,
              dphi_z = r.r22 * p.Y - r.r21 * p.Z;
  // The rotation columns of the two rows of H, pixels per radian.
  const Lanes a0 = -ax * q.RPy, a1 = ax * (r.cz * q.Qz + u * q.Qx), a2 = ax * (dphi_x - u * dphi_z);
  const Lanes b0 = by * q.RPx, b1 = by * (r.sz * q.Qz + v * q.Qx), b2 = by * (dphi_y - v * dphi_z);
  const Lanes axu = ax * u, byv = by * v;
  const Lanes zero{};
  // kRR00, kRR10, kRR11, kRR20
  sums_of(a0 * a0 + b0 * b0, a1 * a0 + b1 * b0, a1 * a1 + b1 * b1, a2 * a0 + b2 * b0, &sums[0]);
  // kRR21, kRR22, kTX0, kTX1
  sums_of(a2 * a1 + b2 * b1, a2 * a2 + b2 * b2, ax * a0, ax * a1, &sums[1]);
  // kTX2, kTT00, kTY0, kTY1
  sums_of(ax * a2, ax * ax, by * b0, by * b1, &sums[2]);
  // kTY2, kTT10, kTT11, kTZ0
  sums_of(by * b2, zero, by * by, -(axu * a0 + byv * b0), &sums[3]);
  // kTZ1, kTZ2, kTT20, kTT21
  sums_of(-(axu * a1 + byv * b1), -(axu * a2 + byv * b2), -(ax * axu), -(by * byv), &sums[4]);
  // kTT22, kUnused, kG0, kG1
  sums_of(axu * axu + byv * byv, zero, e0 * a0 + e1 * b0, e0 * a1 + e1 * b1, &sums[5]);
  // kG2, kG3, kG4, kG5
  sums_of(e0 * a2 + e1 * b2, e0 * ax, e1 * by, -(e0 * axu + e1 * byv), &sums[6]);
}

// The measurement's two steps (vision/src/ekf_measurement.hpp), built for
// whichever instruction set their caller is.
inline bool project(const EkfPoints& points, const Vector6d& x, const EulerTrig& trig,
                    EkfProjection* out) {
  out->pose = Projection(x, trig);
  Lanes residual;
  if (!project_block(points.blocks[0], out->pose, &out->blocks[0], &residual)) return false;
  for (size_t b = 1; b < points.blocks.size(); ++b) {
    Lanes more;
    if (!project_block(points.blocks[b], out->pose, &out->blocks[b], &more)) return false;
    residual += more;
  }
  // The lanes summed as sums_of sums the others: (0 + 1) + (2 + 3).
  out->residual_squared = (residual[0] + residual[1]) + (residual[2] + residual[3]);
  return true;
}

// The system is made here, while the sums are still in registers: made by
// the update after them, it went through memory twice more on its way to
// the next 6x6 solve, about 9 % of a 4-point solve (bench_solvers, ABBA).
inline void update_system(const EkfPoints& points, const EkfProjection& projection,
                          const SystemWeights& w, UpdateSystem* out) {
  Lanes sums[kTerms / 4];
  block_sums(points.blocks[0], projection.pose, projection.blocks[0], sums);
  for (size_t b = 1; b < points.blocks.size(); ++b) {
    Lanes more[kTerms / 4];
    block_sums(points.blocks[b], projection.pose, projection.blocks[b], more);
    for (int k = 0; k < kTerms / 4; ++k)
      sums[k] += more[k];
  }
  for (int k = 0; k < kTerms / 4; ++k)
    sums[k] = w.prior[k] + w.inv_r * sums[k];
  std::memcpy(out, sums, sizeof(UpdateSystem));
}

bool project_baseline(const EkfPoints& points, const Vector6d& x, const EulerTrig& trig,
                      EkfProjection* out) {
  return project(points, x, trig, out);
}
void system_baseline(const EkfPoints& points, const EkfProjection& projection,
                     const SystemWeights& w, UpdateSystem* out) {
  update_system(points, projection, w, out);
}

#if defined(VISION_AVX2_FMA)
VISION_AVX2_FMA bool project_avx2_fma(const EkfPoints& points, const Vector6d& x,
                                      const EulerTrig& trig, EkfProjection* out) {
  return project(points, x, trig, out);
}
VISION_AVX2_FMA void system_avx2_fma(const EkfPoints& points, const EkfProjection& projection,
                                     const SystemWeights& w, UpdateSystem* out) {
  update_system(points, projection, w, out);
}
#endif

}  // namespace

SystemWeights::SystemWeights(const Symmetric6& prior_information, double inv_r) : inv_r(inv_r) {
  UpdateSystem layout{};
  layout.information = prior_information;
  std::memcpy(prior, &layout, sizeof(UpdateSystem));
}

EkfMeasurement ekf_measurement(EkfInstructionSet set) {
#if defined(VISION_AVX2_FMA)
  if (set == EkfInstructionSet::kAvx2Fma) return {project_avx2_fma, system_avx2_fma};
#endif
  (void)set;
  return {project_baseline, system_baseline};
}

EkfInstructionSet ekf_instruction_set(std::optional<EkfInstructionSet> requested) {
  static const EkfInstructionSet fastest = cpu_runs(EkfInstructionSet::kAvx2Fma)
                                               ? EkfInstructionSet::kAvx2Fma
                                               : EkfInstructionSet::kBaseline;
  return requested && cpu_runs(*requested) ? *requested : fastest;
}

}  // namespace vision::detail

namespace vision {

bool cpu_runs(EkfInstructionSet set) {
  if (set == EkfInstructionSet::kBaseline) return true;
  return detail::cpu_has_avx2_fma();
}

}  // namespace vision
