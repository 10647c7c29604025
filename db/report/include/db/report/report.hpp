// db::report::Report: the document a run database exists for: how far each
// solver is from the truth, at which distance, and whether this run is better
// or worse than a baseline. From one run of a run database it computes
//  - the paper's study (Maidi et al. 2010, §3), per solver and per scope
//    (the pose marker alone, scope "<its id>", "0" by default; "target":
//    every detected marker):
//    reconstruction (reprojection) error (Table 2, Fig. 8), generalization
//    error (Table 3, Fig. 9), the regression estimated = a * true + b with
//    asymptotic standard errors (Table 4), residual RMS and variance
//    (Table 5), mean error, variance, standard deviation and time per pose
//    (Table 6), the ten distance classes over [0.10, 1.00] m (Fig. 11) and
//    estimated against true distance with the fit (Fig. 12), the paper's own
//    values beside ours;
//  - beyond the paper: Deming errors-in-variables regression, jitter against
//    bias, planar ambiguity and flips against distance and viewing angle,
//    efficiency (variance over the Cramér-Rao bound), detection rate and
//    corner quality against marker size, convergence failures, stage times;
//  - with a baseline, every figure beside the baseline's and the differences
//    that exceed their statistical uncertainty,
// and writes it as report.html (self-contained, SVG inline), report.json
// (every figure's numbers) and CSV tables.
//
// Units: distances and distance errors in metres (error = estimated - true),
// image errors in pixels, times in microseconds (solvers) or seconds (stages),
// angles in degrees.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "db/stats/compare.hpp"
#include "db/stats/descriptive.hpp"
#include "db/stats/eiv.hpp"
#include "db/stats/regression.hpp"
#include "db/store/records.hpp"

namespace db::report {

// The input of a report is unusable: the file is missing, not a rig run
// database, of a newer (or older) schema, holds no completed run, or the
// requested run does not exist. The message names the file (and run) and
// what was expected. `rig report` exits with 2.
class ReportInputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The truth of a run's positions recomputed by the caller under another rig
// geometry and camera calibration than the sweep used (`rig report
// --geometry FILE [--calibration FILE]`): the bench read-backs are stored, so
// the true distance, viewing angle, markers in view and Cramér-Rao bounds
// follow from them without sweeping again. db::report does no geometry
// itself: rig (rig/cli) computes these and hands them over.
struct TruthFile {
  std::string role;    // "rig geometry", "camera calibration"
  std::string path;    // as given
  std::string sha256;  // 64 lowercase hex characters of the file's bytes
};

// One position's recomputed truth; fields as in store::PositionRecord (metres,
// degrees, metres per pixel, pixels), absent or empty when not known.
struct PositionTruth {
  std::optional<double> true_distance_m;
  std::optional<double> true_viewing_angle_deg;
  std::vector<store::DistanceBound> distance_bounds;
  std::vector<store::VisibleMarker> visible_markers;
  std::optional<store::TruePose> true_pose;
};

struct RecomputedTruth {
  std::vector<TruthFile> files;  // what the truth was computed from, named in the header
  // By plan index. Replaces the stored truth of every position of the run: a
  // measured position missing here (e.g. no read-back) has no known truth.
  std::map<std::int64_t, PositionTruth> positions;
};

struct ReportOptions {
  // The run to report; unset: the most recent completed run of the file.
  // A run named here may also be aborted or failed (the page says so), but
  // not still running.
  std::optional<std::int64_t> run_id;
  // An IPPE-family estimate counts as ambiguous when its ambiguity_ratio
  // (reprojection error of the better planar solution over that of the
  // worse, in [0, 1]) is at least this: at 0.8 the wrong solution explains
  // the corners within 25 % of the right one's error, i.e. well inside the
  // spread that corner noise gives two fits of the same frame. Lower: more
  // estimates called ambiguous (the rate rises towards 1 at long range);
  // higher: only near-ties.
  double ambiguity_ratio_threshold = 0.8;
  // A flip: the pose marker's rotation (scope "0") differs from the whole
  // target's rotation (scope "target") of the same solver and frame by more
  // than this angle, degrees. A planar flip mirrors the marker about the line
  // of sight and moves its normal by about twice the viewing angle (tens of
  // degrees), while corner noise moves a 5 cm marker's rotation by a few
  // degrees at 1 m; 20 degrees separates the two. Lower: noise counted as
  // flips at long range; higher: flips near frontal views missed.
  double flip_angle_deg = 20.0;
  // Standard deviation of the true distance's random error from position to
  // position (the bench read-back's repeatability), metres: the x error of
  // the Deming regression, whose error variance ratio is delta = (jitter of
  // the estimates)^2 / this^2. 50 um is the repeatability of a ball-screw
  // bench with an encoder read-back; an error of the rig geometry is the same
  // for every position (it moves the intercept, not the points) and does not
  // belong here. Smaller: Deming tends to ordinary least squares; larger:
  // towards the inverse regression. If it exceeds the residual sd of the fit,
  // the data contradict it (the points would scatter at least that much).
  double true_distance_sd_m = 0.00005;
  // Run comparison: a difference is flagged when |difference| > k * its
  // standard error (db::stats::compare_means). 3 flags a true non-change
  // 0.27 % of the time per figure.
  double significance_k = 3.0;
  // Fig. 12 draws at most this many positions per solver (every n-th by plan
  // index); the fit always uses every estimate. Larger: heavier page.
  std::size_t max_points_per_series = 300;
  // Two solvers of one scope coincide when they have the same used estimates
  // per position and their per-position mean |distance error| differ by at
  // most this at every position, metres: they are listed together and drawn
  // once. 0.1 um is a hundredth of the smallest within-position jitter a
  // 1280 px camera gives a 0.1 m target (~10 um), so only solvers that
  // compute the same pose (the same algorithm in two libraries) coincide.
  double coincidence_m = 1e-7;
  // Empty: the truth the sweep stored (its own rig geometry and calibration).
  // Set: called once with the reported run and its measured positions (as
  // stored, without frames, by plan index); what it returns replaces their
  // truth (the baseline keeps its own). Its exceptions propagate.
  std::function<RecomputedTruth(const store::Run& run,
                                const std::vector<store::PositionRecord>& positions)>
      recompute_truth;
};

// One of the ten distance classes of one solver and scope.
struct DistanceClassStudy {
  double lower_m = 0, upper_m = 0;
  stats::Summary error_m;            // estimated - true, every used estimate (Fig. 11)
  stats::Summary reprojection_px;    // Fig. 8
  stats::Summary generalization_px;  // Fig. 9 (scope "0" only; count 0 otherwise)
  // Jitter and bias: with s_p^2 the variance of the distance over the frames
  // of position p and n_p its used frames, jitter = sqrt(sum (n_p-1) s_p^2 /
  // sum (n_p-1)) (pooled within-position sd); bias = mean over positions of
  // (mean_p - true_p), bias_sd its spread over positions. NaN when no
  // position has two used frames (jitter) or none at all (bias).
  std::size_t positions = 0;
  double jitter_m = 0, bias_m = 0, bias_sd_m = 0;
  // Efficiency = jitter^2 / (sigma_corner^2 * mean bound^2) pooled as
  // sum (n_p-1) s_p^2 / sum (n_p-1) sigma^2 b_p^2, with b_p the position's
  // Cramér-Rao distance bound (m/px) for this scope and sigma the class's
  // corner noise (ClassCornerNoise). 1 is an efficient estimator; NaN when
  // bounds or corner noise were not recorded.
  double efficiency = 0;
  std::size_t ambiguity_checked = 0, ambiguous = 0;  // converged estimates with an ambiguity ratio
  std::size_t flip_checked = 0, flips = 0;           // frames with both scopes (scope "0" only)
  // The full pose against the position's true pose (positions that recorded
  // it, schema 4 on; count 0 otherwise), every used estimate: translation
  // error t_est - t_true per axis of the camera frame (x right, y down, z
  // along the optical axis; m) and rotation error, the angle of
  // R_est^T R_true (degrees).
  stats::Summary error_x_m, error_y_m, error_z_m, rotation_error_deg;
};

// The bound behind `efficiency` assumes corner errors independent between
// corners and coordinates (the stored bound is sigma (J^T J)^-1 per px; the
// database keeps neither J nor the corners' error covariance, so the bound
// under correlated errors cannot be computed from it). No unbiased solver
// goes below the true bound: a ratio below 1 says the assumption fails in
// that class, not that the solver beat the bound.
inline bool efficiency_below_bound(const DistanceClassStudy& c) {
  return c.efficiency < 1.0;  // false for NaN
}
// The efficiency a figure may draw as the solver's point: NaN where it is
// below the bound (efficiency_below_bound) or unknown.
inline double efficiency_drawn(const DistanceClassStudy& c) {
  return c.efficiency >= 1.0 ? c.efficiency : std::numeric_limits<double>::quiet_NaN();
}

// Counts by viewing-angle class, for ambiguity and flips.
struct AngleClassStudy {
  double lower_deg = 0, upper_deg = 0;
  std::size_t ambiguity_checked = 0, ambiguous = 0;
  std::size_t flip_checked = 0, flips = 0;
};

// One position's means over its used frames (run comparison pairs them by
// plan index).
struct PositionMeans {
  std::int64_t plan_index = 0;
  double abs_error_m = 0;        // mean |estimated - true|
  double reprojection_px = 0;    // mean reprojection error
  double generalization_px = 0;  // mean generalization error; NaN when absent
};

// Everything about one solver on one scope.
struct SolverStudy {
  std::string solver, scope;
  std::size_t estimates = 0;  // rows in the run
  std::size_t skipped = 0;    // solver not applicable to the scope ("skipped"/"not_applicable")
  std::size_t failed = 0;     // applicable but not converged
  std::size_t used = 0;       // converged with a known true distance: the accuracy figures
  std::map<std::string, std::size_t> failures_by_termination;
  stats::Summary reprojection_px;    // Table 2
  stats::Summary generalization_px;  // Table 3 (scope "0")
  stats::Summary error_m;            // Table 6: estimated - true
  stats::Summary abs_error_m;        // |estimated - true|
  double abs_error_p95_m = 0;        // 95th percentile of |estimated - true| (NaN: none used)
  // 95 % confidence half-width of the mean |error| (abs_error_m.mean), m:
  // t(0.975, n - 1) * sd / sqrt(n) over the n per-position means
  // (position_abs_error_m), because the frames of one position share its
  // pose and are not independent draws, the positions are. NaN below two
  // positions.
  double abs_error_ci95_m = 0;
  stats::Summary relative_error_pct;  // 100 |estimated - true| / true (the paper's "0.81 %")
  stats::Summary time_us;             // every applicable estimate (Table 6)
  // Per-position means (one number per position, independent across
  // positions, unlike frames of one position): what run comparison tests.
  stats::Summary position_abs_error_m, position_reprojection_px, position_generalization_px;
  std::vector<PositionMeans> per_position;        // by plan index
  std::optional<stats::LineFit> ols;              // estimated = a * true + b (Tables 4, 5)
  std::optional<stats::EivFit> deming;            // same line, Deming (errors in both variables)
  double deming_delta = 0;                        // the error variance ratio it used
  std::vector<DistanceClassStudy> classes;        // the ten classes, empty ones included
  std::vector<AngleClassStudy> by_viewing_angle;  // 0-90 degrees in 10 degree classes
  std::size_t ambiguity_checked = 0, ambiguous = 0, flip_checked = 0, flips = 0;
  // The solver (same scope, earlier in the sorted list) whose results this
  // one coincides with (ReportOptions::coincidence_m); "" for none. Such a
  // solver is not drawn again and shares its summary row.
  std::string coincides_with;
  // Fig. 12: per-position mean estimated against true distance (thinned).
  std::vector<double> plot_true_m, plot_estimated_m;
  // The used estimate farthest from the true distance: its position's plan
  // index and its frame (-1: none used), and |estimated - true|, m.
  std::int64_t worst_plan_index = -1;
  int worst_frame_index = -1;
  double worst_abs_error_m = 0;
};

// Corner noise per distance class: pooled within-position standard
// deviation of each detected corner coordinate over the frames of a
// position, sqrt(sum (n-1) s^2 / sum (n-1)) over positions, markers and the
// 8 coordinates, px; NaN with fewer than two frames per position.
struct ClassCornerNoise {
  double lower_m = 0, upper_m = 0;
  double sigma_px = 0;
  std::size_t dof = 0;
};

// Detection against the marker's projected side length at the true pose.
struct MarkerSizeClass {
  double lower_px = 0, upper_px = 0;
  std::size_t expected = 0;  // visible marker x frame
  std::size_t detected = 0;  // of those, detected in the frame
  stats::Summary edge_fit_residual_px;
  double corner_jitter_px = 0;  // pooled within-position sd of the corners, px (NaN: < 2 frames)
};

// A visible marker (at the true pose) that some frame of its position did
// not detect: what explains a dip of the detection rate.
struct MissedMarker {
  std::int64_t plan_index = 0;
  int marker_id = -1;
  double side_px = 0;          // projected side at the true pose
  double true_distance_m = 0;  // NaN: not known
  std::size_t frames = 0, frames_detected = 0;
};

// One detector of the run: its detections against the markers in view and
// their true corners, and its time. Its solvers' figures are the
// SolverStudy entries named series_name(solver, detector, primary).
struct DetectorStudy {
  std::string detector;           // registry name (vision/detectors.hpp)
  bool primary = false;           // the run's primary detector
  std::size_t views_in_view = 0;  // markers in view x frames, over the measured positions
  std::size_t views_found = 0;    // of those, found (each marker once per frame)
  // RMS distance of the found markers' corners from their true corners (the
  // layout projected through the run's camera at the true pose), px, over
  // the detections within 10 px of the truth (a calibration's error is a
  // few px at most; beyond, the id was decoded somewhere else); NaN when
  // none was recorded (runs before schema 5).
  double corner_rms_px = 0;
  std::size_t corners_vs_truth = 0;  // detections it is over
  std::size_t misplaced = 0;         // detections of markers in view farther than 10 px
  // Mean detector time per frame, seconds (stage "detect:DETECTOR"; for the
  // primary detector of a run before schema 5, stage "detect"); NaN: not recorded.
  double time_per_frame_s = 0;
};

// The name of a solver's series in a report: the solver's name for the
// run's primary detector, "SOLVER@DETECTOR" for another detector's corners.
std::string series_name(const std::string& solver, const std::string& detector,
                        const std::string& primary_detector);

struct StageStudy {
  std::string stage;
  stats::Summary seconds;
  double median_s = 0, p95_s = 0;
};

// One compared figure of one solver and scope.
struct ComparedFigure {
  std::string solver, scope;
  std::string figure;  // "mean |distance error| (m)", ...
  double candidate = 0, baseline = 0;
  stats::Difference difference;
  // Whether the figure is one where larger is worse and counts towards a
  // regression: errors and failure rates (times depend on the machine, the
  // line parameters have no "worse" side: they are flagged, not counted).
  bool counted = false;
  // The threshold of the regression verdict: k raised by Bonferroni's
  // correction over the m counted figures of the comparison, so that the
  // chance that a run from the baseline's distributions is called
  // "regressed" is at most that of one comparison at k (0.27 % at k = 3):
  // two-sided P(|T| > regression_k) = P(|z| > k) / m, with T Student's t of
  // the figure's degrees of freedom (difference.dof: n - 1 for a paired mean
  // over n positions, Welch's for unpaired means) or normal when infinite.
  double regression_k = 0;
  // A counted figure significantly larger than the baseline's by
  // regression_k / smaller by it.
  bool worse = false;
  bool better = false;
};

struct RunStudy {
  std::string database;  // path as given
  store::Run run;
  std::size_t positions = 0, failed_positions = 0, frames = 0;
  // Measured positions with no true distance or one outside the ten classes
  // (more than 5 mm outside [0.10, 1.00] m): in the fits, not in the classes.
  std::size_t positions_outside_classes = 0;
  std::size_t estimates = 0;
  std::vector<SolverStudy> solvers;  // sorted by solver, then scope ("0" before "target")
  std::vector<ClassCornerNoise> corner_noise;
  std::vector<MarkerSizeClass> marker_sizes;  // empty when visible markers were not recorded
  std::vector<MissedMarker> missed_markers;   // by plan index, then marker id
  bool visible_markers_recorded = false;
  // Left out of every detection figure because of a non-finite value (a
  // detector or simulator bug): detections with a non-finite corner
  // coordinate or edge-fit residual (not counted as detected), and visible
  // markers (marker x position) with a non-finite projected side length.
  std::size_t nonfinite_detections = 0, nonfinite_visible_markers = 0;
  bool distance_bounds_recorded = false;
  bool viewing_angles_recorded = false;
  bool true_poses_recorded = false;  // positions with a true pose (schema 4 on)
  // Per distance class, the plan indices of its first positions with frames
  // (at most 4), for pictures.
  std::vector<std::vector<std::int64_t>> class_example_positions;
  std::vector<StageStudy> stages;
  std::vector<DetectorStudy> detectors;  // the primary first
  std::vector<store::RunEvent> events;
  ReportOptions options;
  // Set when options.recompute_truth replaced the stored truth: what it
  // returned (the files it names are in the run header and report.json).
  std::optional<RecomputedTruth> truth;

  // The solvers that coincide with `s` (whose coincides_with is s.solver),
  // in order.
  std::vector<std::string> coinciding(const SolverStudy& s) const;
  // nullptr when the run has no such solver and scope.
  const SolverStudy* find(const std::string& solver, const std::string& scope) const;
};

// "DB[:RUN]" of --baseline: the path and, when the text ends in ":<digits>",
// the run id. Throws ReportInputError for an empty path.
struct RunReference {
  std::string database;
  std::optional<std::int64_t> run_id;
  static RunReference parse(const std::string& text);
};

// Loads the run and computes its study. Opens the file read-only (never
// creates or migrates it). Throws ReportInputError for unusable input (see
// above); StoreError for a failure while reading.
RunStudy study_run(const std::string& database, const ReportOptions& options);

// Whether the two runs ran the same plan: their run descriptions' plan_json
// are identical text (the plan's positions in plan-index order), so that plan
// index i is the same commanded position in both and the runs' per-position
// errors can be paired. Two plans that differ only in formatting count as
// different (Welch is used then: valid, only less sensitive).
bool same_plan_of(const RunStudy& candidate, const RunStudy& baseline);

// Every figure of `candidate` against `baseline`, for the solvers and scopes
// both have: mean |distance error|, mean reprojection and generalization error
// (per-position means: paired by plan index when the runs ran the same plan,
// see same_plan_of, and share at least two measured positions, the mean
// difference over its standard error, which removes the spread of the errors
// over distance from the comparison; else Welch on the two runs'
// per-position means, the figure's name saying why), failure rate (pooled
// two-proportion standard error), OLS slope and intercept, mean time per pose, and per distance
// class the bias (mean over positions of their mean error; shown, not
// counted). difference.significant uses k; worse and better the
// family-wise regression_k.
// k is a threshold in standard errors, a quantile of the standard normal
// distribution (k = 3: two-sided tail 0.27 %); regression_k is the normal
// quantile of that tail divided by the number of counted figures.
// Precondition: k > 0 and finite; throws stats::StatsError otherwise.
std::vector<ComparedFigure> compare_runs(const RunStudy& candidate, const RunStudy& baseline,
                                         double k);

// True when some counted figure of a comparison got significantly worse
// (ComparedFigure::worse): the verdict of Report::regressed and of
// report.json's "regressed".
bool regressed(const std::vector<ComparedFigure>& comparison);

// The paper's own values for a solver (Maidi et al. 2010, Tables 2-6),
// for "analytic", "hybrid_oi", "ekf", "hybrid_ekf"; nullopt for others.
struct PaperValues {
  std::string label;  // the paper's column heading, e.g. "H. EKF"
  double reprojection_mean_px, reprojection_variance, reprojection_sd_px;        // Table 2
  double generalization_mean_px, generalization_variance, generalization_sd_px;  // Table 3
  double slope, slope_se, intercept_m, intercept_se_m;                           // Table 4
  double residual_rms_m, residual_variance;                                      // Table 5
  double mean_error_m, error_variance, error_sd_m, time_us;                      // Table 6
  double time_per_pose_us;  // paper §3: per pose, Pentium III 1.1 GHz
};
std::optional<PaperValues> paper_values(const std::string& solver);

// What Report::write produced.
struct ReportFiles {
  std::string html, json;
  std::vector<std::string> csv;
};

// A frame the report shows as a picture, and why (Report::frames_to_show).
struct FrameToShow {
  std::int64_t plan_index = 0;
  int frame_index = 0;
  std::string reason;  // e.g. "class 0.10-0.19 m", "worst of hybrid_ekf (scope 0): +2.31 mm"
};

// A frame drawn for the page by the caller (db knows no image format): PNG
// bytes of width x height px, the frame scaled by `scale` (picture px per
// frame px) with the detections drawn, and what was drawn, for the caption.
struct FramePicture {
  FrameToShow frame;
  std::string png;
  int width = 0, height = 0;
  double scale = 1;
  std::string drawn;  // e.g. "4 markers detected: corners and ids in orange"
};

class Report {
 public:
  // Computes the study of `database` (see study_run); with a baseline, also
  // the baseline's study (its run: baseline->run_id, else its latest
  // completed one) and the comparison. Throws ReportInputError for unusable
  // input of either file, StoreError for a failure while reading, and
  // stats::StatsError if options.significance_k is not a finite k > 0.
  Report(const std::string& database, const ReportOptions& options,
         const std::optional<RunReference>& baseline = std::nullopt);

  const RunStudy& study() const { return study_; }
  const std::optional<RunStudy>& baseline() const { return baseline_; }
  const std::vector<ComparedFigure>& comparison() const { return comparison_; }
  // True when some solver got significantly worse than the baseline
  // (db::report::regressed of comparison()); false without a baseline.
  bool regressed() const;

  // Writes report.html, report.json and the CSV tables into directory
  // out_dir (created if missing). Throws std::runtime_error naming the file
  // when one cannot be written.
  ReportFiles write(const std::string& out_dir) const;

  // The frames worth a picture: the first `per_class` stored positions with
  // frames of each distance class (their frame 0) and, per solver of the
  // pose marker's scope, the frame of its worst used estimate; each frame
  // once, by plan index.
  std::vector<FrameToShow> frames_to_show(std::size_t per_class = 2) const;
  // The pictures write() puts on the page (section "frames") and lists in
  // report.json. Without any, the page says how to get them.
  void set_pictures(std::vector<FramePicture> pictures) { pictures_ = std::move(pictures); }

 private:
  std::vector<FramePicture> pictures_;
  RunStudy study_;
  std::optional<RunStudy> baseline_;
  std::vector<ComparedFigure> comparison_;
};

}  // namespace db::report
