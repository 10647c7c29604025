// A synthetic sweep written through db::store::Store with known truth, for the
// report's tests and benchmark: every solver's estimated distance is
// slope * true + intercept + Normal(0, frame_sd) on every frame and scope, so
// a report must recover the slope, intercept and spread it was given; corners
// jitter by Normal(0, corner_noise_px) per coordinate and frame, so the
// report's corner noise and efficiency have known values too.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "db/store/records.hpp"

namespace rig_test {

struct SyntheticSolver {
  std::string name;
  double slope = 1.0;
  double intercept_m = 0.0;
  // Standard deviation of each estimate about slope * true + intercept, m.
  double frame_sd_m = 0.002;
  // If > 0, overrides frame_sd_m: frame sd = sqrt(efficiency) *
  // corner_noise_px * bound(d), so that the solver's efficiency (variance over
  // the Cramér-Rao bound) is this number.
  double efficiency = 0.0;
  double reprojection_mean_px = 0.5, reprojection_sd_px = 0.1;  // clipped at 0.01 px
  double generalization_mean_px = 10.0, generalization_sd_px = 3.0;
  // Fraction of applicable estimates written with converged = false
  // (termination "max_iterations").
  double failure_rate = 0.0;
  // Needs exactly one square (like "analytic"): on scope "target" it is
  // written converged = false, termination "not_applicable".
  bool single_square_only = false;
  // IPPE-family: every estimate carries this ambiguity ratio (NaN: none).
  double ambiguity_ratio = std::numeric_limits<double>::quiet_NaN();
  // Fraction of frames in which the scope-"0" rotation is turned 60 degrees
  // about the camera x axis from the scope-"target" rotation (a flip).
  double flip_rate = 0.0;
  double time_us = 50.0;
  // Non-empty: this solver's estimates are those of the solver of that name
  // (listed earlier) in every frame, renamed: the same pose computed by a
  // second implementation. Its other fields are not used.
  std::string same_draws_as;
};

struct SyntheticRunSpec {
  std::uint64_t seed = 1;
  int positions = 200;  // plan size; true distances evenly spaced over the range
  int frames_per_position = 3;
  double min_distance_m = 0.12, max_distance_m = 0.98;
  std::vector<SyntheticSolver> solvers;
  double corner_noise_px = 0.2;
  // Cramér-Rao distance bound of a position, m/px: bound_at_1m * d^2 (scope
  // "0"; half of it for "target").
  double bound_at_1m_m_per_px = 0.01;
  // The last failed_positions plan indices are stored as failed, without frames.
  int failed_positions = 0;
  // Positions appended last plan index first (the same rows otherwise), as
  // positions measured again after a resume land after those stored since:
  // row order is then not plan order.
  bool stored_in_reverse = false;
  // Markers 0-3 are visible; marker 3 is never detected beyond this distance,
  // m (so the detection rate falls for the smallest markers).
  double marker3_lost_beyond_m = 0.8;
  // false: write positions as a schema-1 writer would have (no viewing angle,
  // bounds, visible markers or true pose).
  bool record_physics = true;
  // A detector bug: marker 1's detection in frame 0 of plan index 0 gets an
  // infinite corner coordinate, and marker 2's visible side at plan index 1
  // is infinite.
  bool plant_nonfinite_detection = false;
  db::store::RunStatus status = db::store::RunStatus::kCompleted;  // kRunning: left running
  bool durable_commits = false;  // the fixture does not need fsyncs
};

// The paper's four solvers with modest, distinct errors (for the tests).
std::vector<SyntheticSolver> paper_like_solvers();

struct SyntheticRun {
  std::int64_t run_id = 0;
  std::size_t estimates = 0;  // rows written to estimates
};

// Appends one run to the database at path (created if missing).
SyntheticRun write_synthetic_run(const std::string& path, const SyntheticRunSpec& spec);

// True distance of plan index i of a spec, m.
double synthetic_true_distance(const SyntheticRunSpec& spec, int i);
// Cramér-Rao bound of scope "0" at distance d, m/px.
double synthetic_bound(const SyntheticRunSpec& spec, double d);

}  // namespace rig_test
