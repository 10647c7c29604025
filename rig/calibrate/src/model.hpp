// The projection model of the bundle adjustment, shared by the solver and
// the prediction of held-out positions (calibration.hpp states it).
#pragma once

#include <ceres/rotation.h>

#include <array>

#include "rig/calibrate/calibration.hpp"

namespace rig::calibrate::detail {

// Parameter block layout: intrinsics (13: fx fy cx cy k1 k2 p1 p2 k3 s1 s2 s3
// s4), camera misalignment (3, radians), target tilt (3, radians),
// camera-to-target offset at bench zero d (3, m), the sheet's print scale
// error s (1: the sheet is (1 + s) times its layout).
constexpr int kThinPrism = 9, kMisalignment = 13, kTilt = 16, kOffset = 19, kScale = 22;

// Projects target point P (m, as laid out; printed at (1 + s) P) with the
// carriage at (x_m, y_m) to distorted pixels. R_nominal * v = (v2, -v0, -v1); R_nominal^T * w =
// (-w1, -w2, w0) (vision::RigGeometry::R_bench_nominal).
template <typename T>
void project(const T* p, const double P[3], double x_m, double y_m, T uv[2]) {
  const T scale = T(1) + p[kScale];
  const T P_t[3] = {scale * P[0], scale * P[1], scale * P[2]};
  T q[3];
  ceres::AngleAxisRotatePoint(p + kTilt, P_t, q);  // Rot(tilt) P
  // p_bench relative to the camera centre: R_nominal q + d - carriage
  const T w[3] = {q[2] + p[kOffset] - T(x_m), -q[0] + p[kOffset + 1] - T(y_m),
                  -q[1] + p[kOffset + 2]};
  const T w_nominal[3] = {-w[1], -w[2], w[0]};
  const T minus_m[3] = {-p[kMisalignment], -p[kMisalignment + 1], -p[kMisalignment + 2]};
  T c[3];
  ceres::AngleAxisRotatePoint(minus_m, w_nominal, c);  // Rot(m)^T R_nominal^T w
  const T x = c[0] / c[2], y = c[1] / c[2];
  const T r2 = x * x + y * y;
  const T radial = T(1) + p[4] * r2 + p[5] * r2 * r2 + p[8] * r2 * r2 * r2;
  const T* s = p + kThinPrism;
  const T xd =
      x * radial + T(2) * p[6] * x * y + p[7] * (r2 + T(2) * x * x) + r2 * (s[0] + s[1] * r2);
  const T yd =
      y * radial + p[6] * (r2 + T(2) * y * y) + T(2) * p[7] * x * y + r2 * (s[2] + s[3] * r2);
  uv[0] = p[0] * xd + p[2];
  uv[1] = p[1] * yd + p[3];
}

using Parameters = std::array<double, kParameterCount>;

// The parameters of a camera, a geometry (d = t_bench_target - t_carriage_cam)
// and a print scale error.
Parameters parameters_of(const vision::Camera& camera, const vision::RigGeometry& geometry,
                         double target_scale_error = 0);
// The camera of the parameters (size of `like`).
vision::Camera camera_of(const Parameters& p, const vision::Camera& like);
// The geometry of the parameters, keeping the camera offset of `nominal`.
vision::RigGeometry geometry_of(const Parameters& p, const vision::RigGeometry& nominal);

}  // namespace rig::calibrate::detail
