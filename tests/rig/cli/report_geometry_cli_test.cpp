// `rig report DB --geometry FILE [--calibration FILE]`: a run's truth
// recomputed from its stored read-backs under another rig geometry. Two runs
// with the same detections and estimates, one recorded under geometry A and
// one under geometry B (truth by rig::sweep::ground_truth_at, as the sweep
// computes it): the first reported with --geometry B must give the second's
// figures exactly.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "db/store/sha256.hpp"
#include "db/store/store.hpp"
#include "file_bytes.hpp"
#include "rig/sweep/ground_truth.hpp"
#include "rig_command.hpp"
#include "store_fixture.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using rig_test::RigRun;
using rig_test::run_rig;

using Scratch = db_test::ScratchDir;

// The simulated rig's nominal geometry, and one 1.5 mm and a few tenths of a
// degree away from it, as a calibration would move it.
const char* const kGeometryA =
    "[camera_mount]\noffset_mm = [0.0, 0.0, 0.0]\nmisalignment_deg = [0.3, -0.2, 0.5]\n"
    "[target]\norigin_mm = [1000.0, 150.0, 0.0]\ntilt_deg = [1.0, -1.5, 0.0]\n";
const char* const kGeometryB =
    "[camera_mount]\noffset_mm = [0.0, 0.0, 0.0]\nmisalignment_deg = [0.1, 0.2, 0.45]\n"
    "[target]\norigin_mm = [1001.5, 149.0, 0.7]\ntilt_deg = [0.6, -1.2, 0.1]\n";

// A run with the truth of `geometry` and estimates drawn from `seed` (the
// same seed: the same estimates and detections whatever the geometry).
void write_run(const std::string& db, const std::string& geometry_path, std::uint64_t seed) {
  const vision::RigGeometry geometry = vision::RigGeometry::load(geometry_path);
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::Target target = vision::Target::paper_default();
  db::store::Store store(db);
  db::store::RunDescription d;
  d.config_json = "{\"frames_per_position\":2}";
  d.plan_json = "{\"kind\":\"grid\"}";
  d.plan_size = 27;
  d.sweep_file = {"sweep.toml", "# test\n", ""};
  d.rig_geometry = {geometry_path, rig_test::file_bytes(geometry_path), ""};
  d.software_version = "test";
  d.library_versions_json = "{}";
  d.host = "test";
  const std::int64_t run = store.start_run(d);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int i = 0; i < 27; ++i) {
    db::store::PositionRecord p;
    p.plan_index = i;
    p.commanded_x_mm = 100.0 * (i / 3);
    p.commanded_y_mm = 100.0 + 50.0 * (i % 3);
    p.measured_x_mm = p.commanded_x_mm + 0.003;
    p.measured_y_mm = p.commanded_y_mm - 0.002;
    const rig::sweep::GroundTruth truth =
        rig::sweep::ground_truth_at(geometry, camera, target, *p.measured_x_mm, *p.measured_y_mm);
    p.true_distance_m = truth.distance_m;
    p.true_viewing_angle_deg = truth.viewing_angle_deg;
    p.distance_bounds = truth.distance_bounds;
    p.visible_markers = truth.visible_markers;
    p.true_pose = rig::sweep::stored_true_pose(truth.T_cam_target);
    const double nominal_m = 1.0 - 0.1 * (i / 3);  // what both runs' solvers see, roughly
    for (int f = 0; f < 2; ++f) {
      db::store::FrameRecord frame;
      frame.index = f;
      frame.host_timestamp_ns = 1'700'000'000'000'000'000LL + 1'000'000'000LL * i + f;
      frame.source = "test";
      db::store::DetectionRecord det;
      det.marker_id = 0;
      det.corners_px = {300, 250, 340, 250, 340, 290, 300, 290};
      det.contrast = 150;
      frame.detections.push_back(det);
      for (const char* solver : {"ippe", "lm"})
        for (const char* scope : {"0", "target"}) {
          db::store::EstimateRecord e;
          e.solver = solver;
          e.scope = scope;
          e.R_cam_target = {1, 0, 0, 0, 1, 0, 0, 0, 1};
          e.distance_m = nominal_m + 0.001 * normal(rng);
          e.t_cam_target_m = {0, 0, e.distance_m};
          e.reprojection_error_px = 0.1;
          e.converged = true;
          e.termination = "converged";
          e.time_us = 10;
          frame.estimates.push_back(e);
        }
      p.frames.push_back(std::move(frame));
    }
    store.append_position(run, p);
  }
  store.finish_run(run, db::store::RunStatus::kCompleted, "");
}

json report_json(const Scratch& dir, const std::string& args, const std::string& out) {
  const RigRun r = run_rig("report " + args + " --out " + dir.file(out));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return json::parse(rig_test::file_bytes(dir.file(out + "/report.json")));
}

// What depends on the truth: every solver's figures, the detection figures.
json truth_dependent(const json& report) {
  const json& s = report["study"];
  return {s["solvers"], s["marker_sizes"], s["missed_markers"], s["positions_outside_classes"]};
}

TEST(RigReportGeometry, RecomputedTruthEqualsTheRunRecordedUnderThatGeometry) {
  const Scratch dir;
  const std::string a = dir.write("a.toml", kGeometryA), b = dir.write("b.toml", kGeometryB);
  write_run(dir.file("a.db"), a, 11);
  write_run(dir.file("b.db"), b, 11);
  const json a_as_b = report_json(dir, dir.file("a.db") + " --geometry " + b, "a_as_b");
  const json under_b = report_json(dir, dir.file("b.db"), "b");
  const json under_a = report_json(dir, dir.file("a.db"), "a");
  EXPECT_EQ(truth_dependent(a_as_b), truth_dependent(under_b));
  // The check can fail: 1.5 mm and tenths of a degree change every error.
  EXPECT_NE(truth_dependent(under_a), truth_dependent(under_b));
  // report.json and the header say where the truth came from.
  EXPECT_EQ(under_a["study"]["truth"]["source"], "stored");
  const json& truth = a_as_b["study"]["truth"];
  EXPECT_EQ(truth["source"], "recomputed");
  ASSERT_EQ(truth["files"].size(), 2u);
  EXPECT_EQ(truth["files"][0]["role"], "rig geometry");
  EXPECT_EQ(truth["files"][0]["path"], b);
  EXPECT_EQ(truth["files"][0]["sha256"], db::store::sha256_hex(kGeometryB));
  const std::string html = rig_test::file_bytes(dir.file("a_as_b/report.html"));
  EXPECT_NE(html.find("recomputed from the read-backs with rig geometry " + b + " (sha256 " +
                      db::store::sha256_hex(kGeometryB).substr(0, 12) + ")"),
            std::string::npos);
}

TEST(RigReportGeometry, ACalibrationFileIsNamedWithItsHash) {
  const Scratch dir;
  const std::string b = dir.write("b.toml", kGeometryB);
  write_run(dir.file("b.db"), b, 3);
  const std::string camera = RIG_SOURCE_DIR "/config/cameras/sony_xc555.yaml";
  ASSERT_TRUE(fs::exists(camera)) << camera;
  const json j =
      report_json(dir, dir.file("b.db") + " --geometry " + b + " --calibration " + camera, "out");
  const json& files = j["study"]["truth"]["files"];
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[1]["role"], "camera calibration");
  EXPECT_EQ(files[1]["sha256"], db::store::sha256_hex(rig_test::file_bytes(camera)));
}

TEST(RigReportGeometry, ErrorsNameTheFileAndTheKey) {
  const Scratch dir;
  const std::string a = dir.write("a.toml", kGeometryA);
  write_run(dir.file("a.db"), a, 5);
  const std::string missing = dir.file("missing.toml");
  RigRun r =
      run_rig("report " + dir.file("a.db") + " --geometry " + missing + " --out " + dir.file("o1"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--geometry " + missing + ": no such file"), std::string::npos) << r.err;
  const std::string bad =
      dir.write("bad.toml",
                "[camera_mount]\noffset_mm = [0.0, 0.0, 0.0]\nmisalignment_deg = [0.3, -0.2]\n"
                "[target]\norigin_mm = [1000.0, 150.0, 0.0]\ntilt_deg = [1.0, -1.5, 0.0]\n");
  r = run_rig("report " + dir.file("a.db") + " --geometry " + bad + " --out " + dir.file("o2"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(bad), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("misalignment_deg"), std::string::npos) << r.err;
  r = run_rig("report " + dir.file("a.db") + " --calibration " + a + " --out " + dir.file("o3"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("without --geometry"), std::string::npos) << r.err;
  const std::string bad_camera = dir.write("camera.yaml", "%YAML:1.0\nfoo: 1\n");
  r = run_rig("report " + dir.file("a.db") + " --geometry " + a + " --calibration " + bad_camera +
              " --out " + dir.file("o4"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(bad_camera), std::string::npos) << r.err;
}

}  // namespace
