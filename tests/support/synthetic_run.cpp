#include "synthetic_run.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "db/store/store.hpp"

namespace rig_test {

std::vector<SyntheticSolver> paper_like_solvers() {
  SyntheticSolver analytic;
  analytic.name = "analytic";
  analytic.slope = 1.008;
  analytic.intercept_m = 0.007;
  analytic.single_square_only = true;
  SyntheticSolver hybrid_oi;
  hybrid_oi.name = "hybrid_oi";
  hybrid_oi.slope = 1.004;
  hybrid_oi.intercept_m = 0.003;
  hybrid_oi.frame_sd_m = 0.0015;
  SyntheticSolver ekf;
  ekf.name = "ekf";
  ekf.slope = 1.02;
  ekf.intercept_m = -0.01;
  ekf.frame_sd_m = 0.01;
  ekf.failure_rate = 0.05;
  ekf.time_us = 5000;
  SyntheticSolver ippe;
  ippe.name = "ippe";
  ippe.slope = 1.0;
  ippe.intercept_m = 0.0;
  ippe.efficiency = 2.0;
  ippe.ambiguity_ratio = 0.9;
  ippe.flip_rate = 0.1;
  return {analytic, hybrid_oi, ekf, ippe};
}

double synthetic_true_distance(const SyntheticRunSpec& spec, int i) {
  const int n = std::max(2, spec.positions);
  return spec.min_distance_m +
         (spec.max_distance_m - spec.min_distance_m) * static_cast<double>(i) / (n - 1);
}

double synthetic_bound(const SyntheticRunSpec& spec, double d) {
  return spec.bound_at_1m_m_per_px * d * d;
}

namespace {

db::store::RunDescription description(const SyntheticRunSpec& spec) {
  db::store::RunDescription d;
  d.config_json = "{\"frames_per_position\":" + std::to_string(spec.frames_per_position) +
                  ",\"synthetic\":true}";
  // The plan is the positions' true distances: two specs with different
  // ranges ran different plans.
  d.plan_json = "{\"kind\":\"synthetic\",\"positions\":" + std::to_string(spec.positions) +
                ",\"min_distance_m\":" + std::to_string(spec.min_distance_m) +
                ",\"max_distance_m\":" + std::to_string(spec.max_distance_m) + "}";
  d.plan_size = spec.positions;
  d.sweep_file = {"synthetic.toml", "# synthetic\n", ""};
  d.camera_calibration = {"xc555.yaml", "%YAML:1.0\n", ""};
  d.target_layout = {"paper.toml", "markers = [0, 1, 2, 3]\n", ""};
  d.rig_geometry = {"geometry.toml", "\n", ""};
  d.bench_profile = {"sim.toml", "\n", ""};
  d.software_version = "test";
  d.library_versions_json = "{}";
  d.host = "synthetic";
  return d;
}

// Rotation by angle about the x axis, row-major.
std::array<double, 9> rotation_x(double angle_rad) {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  return {1, 0, 0, 0, c, -s, 0, s, c};
}

// The run's random draws, from one generator in the order the run makes them.
class Draws {
 public:
  explicit Draws(std::uint64_t seed) : rng_(seed) {}
  double normal() { return normal_(rng_); }
  double uniform() { return uniform_(rng_); }

 private:
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
};

// Plan index i's bench position and truth, without frames or physics.
db::store::PositionRecord position_at(const SyntheticRunSpec& spec, int i) {
  db::store::PositionRecord p;
  p.plan_index = i;
  const double d = synthetic_true_distance(spec, i);
  p.commanded_x_mm = 1000.0 * d;
  p.commanded_y_mm = 0.0;
  p.measured_x_mm = p.commanded_x_mm;
  p.measured_y_mm = 0.0;
  p.true_distance_m = d;
  p.settle_time_s = 0.2;
  return p;
}

// Viewing angle, Cramér-Rao bounds of both scopes and the four visible
// markers of a measured position (side_px: each marker's side).
void add_physics(const SyntheticRunSpec& spec, double side_px, db::store::PositionRecord& p) {
  const int i = static_cast<int>(p.plan_index);
  const double d = *p.true_distance_m;
  p.true_viewing_angle_deg = 60.0 * std::fmod(0.37 * i, 1.0);
  p.distance_bounds = {{"0", synthetic_bound(spec, d)}, {"target", 0.5 * synthetic_bound(spec, d)}};
  // The target straight ahead: the estimates' pose (add_estimates) is
  // identity and (0, 0, estimated distance), so the z error is the distance
  // error, x and y errors are 0 and the rotation error is 0 (60 degrees on a
  // flipped frame).
  p.true_pose = db::store::TruePose{{1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 0, d}};
  for (int m = 0; m < 4; ++m) {
    const bool planted = spec.plant_nonfinite_detection && i == 1 && m == 2;
    p.visible_markers.push_back({m, planted ? HUGE_VAL : side_px});
  }
}

void add_stage_times(const SyntheticRunSpec& spec, db::store::PositionRecord& p) {
  p.stage_times = {{"move", 0.5}, {"settle", 0.2}, {"capture", 0.03}, {"detect", 0.004}};
  for (const SyntheticSolver& s : spec.solvers)
    p.stage_times.push_back({"solve:" + s.name, 1e-6 * s.time_us * spec.frames_per_position});
  p.stage_times.push_back({"store", 0.002});
}

// Markers 0-3 side by side as squares of side_px, each corner jittered;
// marker 3 lost beyond marker3_lost_beyond_m.
void add_detections(const SyntheticRunSpec& spec, int i, double d, double side_px, Draws& draws,
                    db::store::FrameRecord& frame) {
  for (int m = 0; m < 4; ++m) {
    if (m == 3 && d > spec.marker3_lost_beyond_m) continue;
    db::store::DetectionRecord det;
    det.marker_id = m;
    const double x0 = 100.0 + 3.0 * side_px * m, y0 = 200.0;
    const double square[8] = {x0,           y0,           x0 + side_px, y0,
                              x0 + side_px, y0 + side_px, x0,           y0 + side_px};
    for (int c = 0; c < 8; ++c)
      det.corners_px[c] = square[c] + spec.corner_noise_px * draws.normal();
    if (spec.plant_nonfinite_detection && i == 0 && frame.index == 0 && m == 1)
      det.corners_px[3] = HUGE_VAL;
    det.contrast = 150;
    det.edge_fit_residual_px = 0.1 + 2.0 / side_px;
    frame.detections.push_back(det);
  }
}

// One solver's estimates of one frame on scopes "0" and "target".
void add_estimates(const SyntheticRunSpec& spec, const SyntheticSolver& s, double d, Draws& draws,
                   db::store::FrameRecord& frame) {
  const double sd = s.efficiency > 0
                        ? std::sqrt(s.efficiency) * spec.corner_noise_px * synthetic_bound(spec, d)
                        : s.frame_sd_m;
  const bool flipped = draws.uniform() < s.flip_rate;
  for (const char* scope : {"0", "target"}) {
    db::store::EstimateRecord e;
    e.solver = s.name;
    e.scope = scope;
    const bool pose_marker = std::string(scope) == "0";
    e.R_cam_target = rotation_x(pose_marker && flipped ? 60.0 * M_PI / 180.0 : 0.0);
    e.time_us = s.time_us;
    if (!pose_marker && s.single_square_only) {
      e.converged = false;
      e.termination = "not_applicable";
      e.time_us = 0.1;
      frame.estimates.push_back(e);
      continue;
    }
    e.distance_m = s.slope * d + s.intercept_m + sd * draws.normal();
    e.t_cam_target_m = {0, 0, e.distance_m};
    e.reprojection_error_px =
        std::max(0.01, s.reprojection_mean_px + s.reprojection_sd_px * draws.normal());
    if (pose_marker) {
      e.generalization_error_px =
          std::max(0.01, s.generalization_mean_px + s.generalization_sd_px * draws.normal());
    }
    e.converged = !(draws.uniform() < s.failure_rate);
    e.termination = e.converged ? "converged" : "max_iterations";
    e.iterations = 5;
    if (!std::isnan(s.ambiguity_ratio)) e.ambiguity_ratio = s.ambiguity_ratio;
    frame.estimates.push_back(e);
  }
}

// The frames of a measured position; returns the number of estimates.
std::size_t add_frames(const SyntheticRunSpec& spec, Draws& draws, db::store::PositionRecord& p) {
  const int i = static_cast<int>(p.plan_index);
  const double d = *p.true_distance_m;
  // Side of a 5 cm marker in px at d with the paper's ~720 px focal length.
  const double side_px = 0.05 * 720.0 / d;
  if (spec.record_physics) add_physics(spec, side_px, p);
  add_stage_times(spec, p);
  std::size_t estimates = 0;
  for (int f = 0; f < spec.frames_per_position; ++f) {
    db::store::FrameRecord frame;
    frame.index = f;
    frame.host_timestamp_ns = 1'700'000'000'000'000'000LL + 1'000'000'000LL * i + f;
    frame.source = "synthetic";
    add_detections(spec, i, d, side_px, draws, frame);
    for (const SyntheticSolver& s : spec.solvers) {
      if (s.same_draws_as.empty()) {
        add_estimates(spec, s, d, draws, frame);
        continue;
      }
      const std::size_t n = frame.estimates.size();
      for (std::size_t k = 0; k < n; ++k) {
        if (frame.estimates[k].solver != s.same_draws_as) continue;
        db::store::EstimateRecord copy = frame.estimates[k];
        copy.solver = s.name;
        frame.estimates.push_back(copy);
      }
    }
    estimates += frame.estimates.size();
    p.frames.push_back(std::move(frame));
  }
  return estimates;
}

}  // namespace

SyntheticRun write_synthetic_run(const std::string& path, const SyntheticRunSpec& spec) {
  db::store::StoreOptions options;
  options.durable_commits = spec.durable_commits;
  db::store::Store store(path, options);
  SyntheticRun out;
  out.run_id = store.start_run(description(spec));
  Draws draws(spec.seed);
  const int ok_positions = spec.positions - spec.failed_positions;
  std::vector<db::store::PositionRecord> positions;
  for (int i = 0; i < spec.positions; ++i) {
    db::store::PositionRecord p = position_at(spec, i);
    if (i >= ok_positions) {
      p.status = db::store::PositionStatus::kFailed;
      p.failure_reason = "synthetic: bench alarm";
      p.stage_times = {{"move", 0.5}};
    } else {
      out.estimates += add_frames(spec, draws, p);
    }
    if (!spec.stored_in_reverse)
      store.append_position(out.run_id, p);
    else
      positions.push_back(std::move(p));
  }
  for (auto p = positions.rbegin(); p != positions.rend(); ++p)
    store.append_position(out.run_id, *p);
  store.record_event(out.run_id, "pause", "synthetic pause", ok_positions / 2);
  store.record_event(out.run_id, "resume", "synthetic resume", ok_positions / 2);
  if (spec.status != db::store::RunStatus::kRunning) {
    store.finish_run(out.run_id, spec.status,
                     spec.status == db::store::RunStatus::kCompleted ? "" : "synthetic end");
  }
  return out;
}

}  // namespace rig_test
