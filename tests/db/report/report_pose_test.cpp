// Per-axis translation and rotation errors against the true pose: a run of
// known poses written through db::store::Store, so every error the report
// gives is known exactly.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "db/report/report.hpp"
#include "db/stats/descriptive.hpp"
#include "file_bytes.hpp"
#include "store_fixture.hpp"

namespace {

using Rotation = std::array<double, 9>;  // row-major

Rotation multiply(const Rotation& a, const Rotation& b) {
  Rotation c{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        c[3 * i + j] += a[3 * i + k] * b[3 * k + j];
  return c;
}

// Rotation by `angle` (rad) about the unit axis u (Rodrigues).
Rotation axis_angle(double ux, double uy, double uz, double angle) {
  const double c = std::cos(angle), s = std::sin(angle), v = 1 - c;
  return {c + ux * ux * v,      ux * uy * v - uz * s, ux * uz * v + uy * s,
          uy * ux * v + uz * s, c + uy * uy * v,      uy * uz * v - ux * s,
          uz * ux * v - uy * s, uz * uy * v + ux * s, c + uz * uz * v};
}

constexpr int kPositions = 30;
constexpr int kFrames = 3;
constexpr double kRotationErrorDeg = 0.3;
// The translation error of frame k: known per axis, different per frame so
// that the sd is known too.
std::array<double, 3> translation_error(int k) {
  return {1e-3 + 1e-4 * k, -2e-4, 5e-5 * (k - 1)};
}

// Positions from 0.105 m to 0.975 m; the target tilted 20 degrees and
// off-axis, every estimate off by translation_error(frame) and rotated by
// kRotationErrorDeg about an oblique axis.
void write_run(const std::string& path, bool record_pose) {
  db::store::Store store(path);
  const std::int64_t run = store.start_run(db_test::make_run_description(kPositions));
  for (int i = 0; i < kPositions; ++i) {
    db::store::PositionRecord p;
    p.plan_index = i;
    p.measured_x_mm = p.commanded_x_mm = i;
    p.measured_y_mm = p.commanded_y_mm = 0;
    const double d = 0.105 + 0.03 * i;
    const Rotation R_true = axis_angle(0, 1, 0, 20.0 * M_PI / 180.0);
    const std::array<double, 3> t_true = {0.01, -0.02, std::sqrt(d * d - 0.0005)};
    p.true_distance_m = d;
    if (record_pose) p.true_pose = db::store::TruePose{R_true, t_true};
    for (int k = 0; k < kFrames; ++k) {
      db::store::FrameRecord f;
      f.index = k;
      f.source = "synthetic";
      db::store::EstimateRecord e;
      e.solver = "lm";
      e.scope = "0";
      const double n = std::sqrt(3.0);
      e.R_cam_target =
          multiply(R_true, axis_angle(1 / n, -1 / n, 1 / n, kRotationErrorDeg * M_PI / 180.0));
      for (int a = 0; a < 3; ++a)
        e.t_cam_target_m[a] = t_true[a] + translation_error(k)[a];
      e.distance_m = std::hypot(e.t_cam_target_m[0], e.t_cam_target_m[1], e.t_cam_target_m[2]);
      e.reprojection_error_px = 0.1;
      e.converged = true;
      e.termination = "converged";
      f.estimates.push_back(e);
      p.frames.push_back(f);
    }
    store.append_position(run, p);
  }
  store.finish_run(run, db::store::RunStatus::kCompleted, "");
}

// Rounding: t_est - t_true recovers the written error to a few ulp of |t|
// (< 1 m: 1e-15 m); the rotation angle comes from acos((trace - 1) / 2),
// whose rounding of ~1e-15 in the cosine is ~1e-15 / sin(0.3 deg) = 2e-13 rad.
constexpr double kLengthTolerance = 1e-15;
constexpr double kAngleToleranceDeg = 1e-9;

TEST(ReportPoseErrors, GiveEachAxisAndTheRotationErrorOfKnownPosesPerClass) {
  db_test::ScratchDir dir;
  write_run(dir.file("run.db"), true);
  const db::report::Report report(dir.file("run.db"), db::report::ReportOptions{});
  ASSERT_TRUE(report.study().true_poses_recorded);
  const db::report::SolverStudy* s = report.study().find("lm", "0");
  ASSERT_NE(s, nullptr);
  std::vector<double> x, y, z;
  for (int k = 0; k < kFrames; ++k) {
    x.push_back(translation_error(k)[0]);
    y.push_back(translation_error(k)[1]);
    z.push_back(translation_error(k)[2]);
  }
  std::size_t counted = 0;
  for (const db::report::DistanceClassStudy& c : s->classes) {
    // Three positions per 0.09 m class, each with kFrames estimates.
    ASSERT_EQ(c.rotation_error_deg.count, 3u * kFrames) << c.lower_m;
    counted += c.rotation_error_deg.count;
    const auto expect = [&](const db::stats::Summary& got, const std::vector<double>& frames) {
      const db::stats::Summary want = db::stats::summarize(frames);  // the same per position
      EXPECT_NEAR(got.mean, want.mean, kLengthTolerance) << c.lower_m;
      // Three copies of the frames' values: variance (3n - 3 of n - 1 ...)
      // = var_frames * (n - 1) * 3 / (3n - 1) with n frames.
      const double n = kFrames;
      EXPECT_NEAR(got.variance, want.variance * 3 * (n - 1) / (3 * n - 1), 1e-20) << c.lower_m;
    };
    expect(c.error_x_m, x);
    expect(c.error_y_m, y);
    expect(c.error_z_m, z);
    EXPECT_NEAR(c.rotation_error_deg.mean, kRotationErrorDeg, kAngleToleranceDeg);
    EXPECT_NEAR(c.rotation_error_deg.max, kRotationErrorDeg, kAngleToleranceDeg);
  }
  EXPECT_EQ(counted, static_cast<std::size_t>(kPositions * kFrames));

  // The page has the table and the figures; report.json keeps SI (radians).
  const db::report::ReportFiles files = report.write(dir.file("out"));
  const std::string html = rig_test::file_bytes(files.html);
  for (const char* id : {"pose-errors-0", "pose-x-0", "pose-y-0", "pose-z-0", "pose-rotation-0"})
    EXPECT_NE(html.find(std::string("id=\"") + id + "\""), std::string::npos) << id;
  const nlohmann::json json = nlohmann::json::parse(rig_test::file_bytes(files.json));
  EXPECT_TRUE(json["study"]["true_poses_recorded"].get<bool>());
  const auto& c0 = json["study"]["solvers"][0]["classes"][0]["pose_error"];
  EXPECT_NEAR(c0["rotation_rad"]["mean"].get<double>(), kRotationErrorDeg * M_PI / 180.0, 1e-11);
  EXPECT_NEAR(c0["x_m"]["mean"].get<double>(), 1.1e-3, kLengthTolerance);
  EXPECT_NEAR(c0["y_m"]["mean"].get<double>(), -2e-4, kLengthTolerance);
}

// A run stored without true poses (before schema 4) still reports; the
// per-axis table and figures are left out and the header says why.
TEST(ReportPoseErrors, AreLeftOutWhenTheRunHasNoTruePoses) {
  db_test::ScratchDir dir;
  write_run(dir.file("run.db"), false);
  const db::report::Report report(dir.file("run.db"), db::report::ReportOptions{});
  EXPECT_FALSE(report.study().true_poses_recorded);
  EXPECT_EQ(report.study().find("lm", "0")->classes[0].rotation_error_deg.count, 0u);
  const std::string html = rig_test::file_bytes(report.write(dir.file("out")).html);
  EXPECT_EQ(html.find("id=\"pose-errors-0\""), std::string::npos);
  EXPECT_NE(html.find("not recorded (runs before schema 4)"), std::string::npos);
}

}  // namespace
