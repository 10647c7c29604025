// Helpers of the run-store tests: a scratch directory per test, a run
// description and deterministic positions whose every field depends on the
// plan index, so that a position read back can be compared field by field
// with the one that was written.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "db/store/store.hpp"

namespace db_test {

class ScratchDir {
 public:
  ScratchDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "rig-db-test-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  // Writes `content` to file(name) and returns that path.
  std::string write(const std::string& name, const std::string& content) const {
    std::ofstream(file(name), std::ios::binary) << content;
    return file(name);
  }

 private:
  std::filesystem::path path_;
};

inline db::store::RunDescription make_run_description(std::int64_t plan_size) {
  db::store::RunDescription d;
  d.config_json = R"({"frames_per_position":2,"settle":{"timeout_s":5}})";
  d.plan_json = R"({"kind":"grid","x_mm":[0,100,10],"y_mm":[0,50,10]})";
  d.plan_size = plan_size;
  d.sweep_file = {"config/sweeps/ci.toml", "[plan]\nkind = \"grid\"\n", ""};
  d.camera_calibration = {"calib/xc555.yaml", "%YAML:1.0\ncamera_matrix: []\n", ""};
  d.target_layout = {"targets/paper.toml", "markers = [0, 1, 2, 3]\n", ""};
  d.rig_geometry = {"geometry.toml", "[target]\nx_mm = 1200\n", ""};
  // Bytes a text column would mangle: NUL and invalid UTF-8.
  d.bench_profile = {"profiles/sim.toml", std::string("bin\0\xff\xfe", 6), ""};
  d.software_version = "0.1.0";
  d.library_versions_json = R"({"opencv":"4.6.0","sqlite":"3.40.1","aravis":"0.8.26"})";
  d.host = "test-host";
  return d;
}

// A position with frames x markers detections and solvers x 2 scopes
// estimates per frame; every value is a distinct function of the plan index.
inline db::store::PositionRecord make_position(std::int64_t plan_index, int frames = 2,
                                               int markers = 4, int solvers = 3) {
  const double k = static_cast<double>(plan_index);
  db::store::PositionRecord p;
  p.plan_index = plan_index;
  p.commanded_x_mm = 10.0 * k + 0.25;
  p.commanded_y_mm = -5.0 * k + 0.125;
  p.measured_x_mm = p.commanded_x_mm + 0.003;
  p.measured_y_mm = p.commanded_y_mm - 0.002;
  p.true_distance_m = 0.5 + 0.001 * k;
  p.settle_time_s = 0.2 + 1e-4 * k;
  p.stage_times = {{"move", 0.5 + k}, {"settle", 0.1}, {"capture", 0.03}, {"store", 1e-3}};
  p.true_viewing_angle_deg = 3.0 + 0.01 * k;
  p.distance_bounds = {{"0", 2e-4 + 1e-6 * k}, {"target", 5e-5}};
  for (int m = 0; m < markers; ++m)
    p.visible_markers.push_back({m, 40.0 + m + k / 3.0});
  for (int f = 0; f < frames; ++f) {
    db::store::FrameRecord frame;
    frame.index = f;
    frame.camera_timestamp_ns = 1'000'000'000LL * plan_index + f;
    frame.host_timestamp_ns = 1'700'000'000'000'000'000LL + 1'000'000LL * plan_index + f;
    frame.source = "gige:Aravis-Fake-GV01";
    if (f == 0) {
      frame.image_path = "frames/" + std::to_string(plan_index) + "_0.png";
      frame.image_sha256 = std::string(64, 'a');
    }
    for (int m = 0; m < markers; ++m) {
      db::store::DetectionRecord d;
      d.marker_id = m;
      d.rotation = (m + static_cast<int>(plan_index)) % 4;
      for (int c = 0; c < 8; ++c)
        d.corners_px[c] = 100.0 * m + 10.0 * c + k / 7.0 + f;
      d.contrast = 120.5 + m;
      d.bits_corrected = m % 2;
      d.edge_fit_residual_px = 0.05 * (m + 1);
      frame.detections.push_back(d);
    }
    for (int s = 0; s < solvers; ++s) {
      for (const char* scope : {"0", "target"}) {
        db::store::EstimateRecord e;
        e.solver = "solver_" + std::to_string(s);
        e.scope = scope;
        for (int r = 0; r < 9; ++r)
          e.R_cam_target[r] = std::sin(k + r + s);
        e.t_cam_target_m = {0.01 * s, -0.02, 0.5 + 0.001 * k};
        e.distance_m = 0.5 + 0.001 * k + 1e-5 * s;
        e.reprojection_error_px = 0.3 + 0.01 * s;
        if (std::string(scope) == "0") e.generalization_error_px = 9.5 + s;
        e.iterations = 3 * s;
        e.converged = s % 3 != 2;
        e.termination = e.converged ? "converged" : "max_iterations";
        e.time_us = 19.0 + s;
        if (s == 1) e.ambiguity_ratio = 0.25;
        frame.estimates.push_back(e);
      }
    }
    p.frames.push_back(frame);
  }
  return p;
}

}  // namespace db_test
