// The tables of the report: the paper's Tables 2-6 with the paper's values
// beside ours, and the tables of the statistics beyond the paper.
#include <algorithm>
#include <cmath>

#include "report_data.hpp"
#include "report_document.hpp"
#include "report_units.hpp"

namespace db::report {
namespace {

html::Cell text(const std::string& t, const std::string& css = "") {
  return {t, css, ""};
}
// A number in SI (or the unit `q` names); the page shows it converted
// (report_units.hpp), JSON and CSV as it is.
html::Cell number(double v, Quantity q = Quantity::kPlain, const std::string& css = "num") {
  return quantity_cell(v, q, css);
}
constexpr Quantity kM = Quantity::kLength, kM2 = Quantity::kArea, kS = Quantity::kDuration,
                   kUs = Quantity::kMicroseconds, kPx = Quantity::kPixels,
                   kPx2 = Quantity::kPixelsSq, kPct = Quantity::kPercent,
                   kRate = Quantity::kFraction;
html::Cell count(std::size_t n) {
  return {std::to_string(n), "num", ""};
}

// This run's study of a solver and scope, then the baseline's if it has one.
std::vector<std::pair<const SolverStudy*, std::string>> with_baseline(const ReportInput& in,
                                                                      const SolverStudy& s) {
  std::vector<std::pair<const SolverStudy*, std::string>> out{{&s, "this run"}};
  if (in.baseline) {
    if (const SolverStudy* b = in.baseline->find(s.solver, s.scope)) out.push_back({b, "baseline"});
  }
  return out;
}

// Rows of one table for every solver of the scope: ours, the baseline's
// (when there is one) and the paper's (pose-marker scope, the paper's solvers).
template <class Ours, class Paper>
void solver_rows(const ReportInput& in, const std::string& scope, html::Table& t, Ours ours,
                 Paper paper) {
  for (const SolverStudy& s : in.study.solvers) {
    if (s.scope != scope) continue;
    for (const auto& [study, source] : with_baseline(in, s)) {
      std::vector<html::Cell> row{text(s.solver), text(source)};
      ours(*study, row);
      t.rows.push_back(std::move(row));
    }
    if (scope != "target") {
      if (const auto p = paper_values(s.solver)) {
        std::vector<html::Cell> prow{text(s.solver, "paper"), text("paper: " + p->label, "paper")};
        paper(*p, prow);
        for (html::Cell& c : prow)
          c.css_class = c.css_class.empty() ? "paper" : c.css_class + " paper";
        t.rows.push_back(std::move(prow));
      }
    }
  }
}

std::string tid(const std::string& name, const std::string& scope) {
  return name + "-" + scope;
}

// "lower-upper" of a class, each with `digits` significant digits.
std::string class_range(double lower, double upper, int digits) {
  return num(lower, digits) + "-" + num(upper, digits);
}

// Tables 2 and 3: count, mean, variance and sd of an image error, px, ours
// beside the paper's (over its 1,400 poses).
void add_image_error_table(const ReportInput& in, const std::string& scope, Section& sec,
                           const std::string& name, const std::string& caption,
                           stats::Summary SolverStudy::*ours, double PaperValues::*paper_mean,
                           double PaperValues::*paper_variance, double PaperValues::*paper_sd) {
  html::Table t{tid(name, scope),
                caption,
                {"solver", "source", "n", "mean (px)", "variance (px²)", "sd (px)"},
                {}};
  solver_rows(
      in, scope, t,
      [&](const SolverStudy& s, std::vector<html::Cell>& r) {
        const stats::Summary& e = s.*ours;
        r.insert(r.end(), {count(e.count), number(e.mean, kPx), number(e.variance, kPx2),
                           number(e.sd, kPx)});
      },
      [&](const PaperValues& p, std::vector<html::Cell>& r) {
        r.insert(r.end(), {text("1400"), number(p.*paper_mean, kPx),
                           number(p.*paper_variance, kPx2), number(p.*paper_sd, kPx)});
      });
  sec.table(std::move(t));
}

// Table 4 and the Deming line beside it.
void add_regression_table(const ReportInput& in, const std::string& scope, Section& sec) {
  html::Table t{tid("table4", scope),
                "Regression estimated = a * true + b, m, with asymptotic standard errors "
                "(paper Table 4); Deming errors-in-variables fit beside it (jackknife "
                "standard errors; delta = var(estimate error) / var(true-distance error))",
                {"solver", "source", "n", "a", "se(a)", "b (m)", "se(b) (m)", "Deming a", "se",
                 "Deming b (m)", "se (m)", "delta"},
                {}};
  solver_rows(
      in, scope, t,
      [](const SolverStudy& s, std::vector<html::Cell>& r) {
        const double nan = kNaN;
        r.push_back(count(s.ols ? s.ols->n : 0));
        r.push_back(number(s.ols ? s.ols->slope : nan));
        r.push_back(number(s.ols ? s.ols->slope_se : nan));
        r.push_back(number(s.ols ? s.ols->intercept : nan, kM));
        r.push_back(number(s.ols ? s.ols->intercept_se : nan, kM));
        r.push_back(number(s.deming ? s.deming->slope : nan));
        r.push_back(number(s.deming ? s.deming->slope_se : nan));
        r.push_back(number(s.deming ? s.deming->intercept : nan, kM));
        r.push_back(number(s.deming ? s.deming->intercept_se : nan, kM));
        r.push_back(number(s.deming ? s.deming_delta : nan));
      },
      [](const PaperValues& p, std::vector<html::Cell>& r) {
        r.insert(r.end(), {text("1939"), number(p.slope), number(p.slope_se),
                           number(p.intercept_m, kM), number(p.intercept_se_m, kM), text("n/a"),
                           text("n/a"), text("n/a"), text("n/a"), text("n/a")});
      });
  sec.table(std::move(t));
}

// Table 5: the residuals of the Table 4 regression.
void add_residual_table(const ReportInput& in, const std::string& scope, Section& sec) {
  html::Table t{
      tid("table5", scope),
      "Residuals of the regression (paper Table 5, gnuplot's vocabulary): RMS = "
      "sqrt(SSR / (n - 2)) m, variance = SSR / (n - 2) m²; plain sqrt(SSR / n) beside",
      {"solver", "source", "RMS of residuals (m)", "variance of residuals (m²)", "sqrt(SSR/n) (m)"},
      {}};
  solver_rows(
      in, scope, t,
      [](const SolverStudy& s, std::vector<html::Cell>& r) {
        r.push_back(number(s.ols ? s.ols->residual_sd : kNaN, kM));
        r.push_back(number(s.ols ? s.ols->residual_variance : kNaN, kM2));
        r.push_back(number(s.ols ? s.ols->residual_rms : kNaN, kM));
      },
      [](const PaperValues& p, std::vector<html::Cell>& r) {
        r.insert(r.end(),
                 {number(p.residual_rms_m, kM), number(p.residual_variance, kM2), text("n/a")});
      });
  sec.table(std::move(t));
}

// Table 6: the distance error and the time per pose.
void add_distance_table(const ReportInput& in, const std::string& scope, Section& sec) {
  html::Table t{
      tid("table6", scope),
      "Distance estimation (paper Table 6): error = estimated - true, m; mean "
      "|error| and mean relative error beside; time per pose of every applicable "
      "estimate, µs (the paper's Table 6 times and its per-pose timings of §3 were measured on "
      "a Pentium III at 1.1 GHz; Table 6's are as printed)",
      {"solver", "source", "n", "mean error (m)", "variance (m²)", "sd (m)", "mean |error| (m)",
       "mean |error| / true (%)", "time (µs)", "time sd (µs)", "paper's time per pose (µs)"},
      {}};
  solver_rows(
      in, scope, t,
      [](const SolverStudy& s, std::vector<html::Cell>& r) {
        r.insert(r.end(), {count(s.error_m.count), number(s.error_m.mean, kM),
                           number(s.error_m.variance, kM2), number(s.error_m.sd, kM),
                           number(s.abs_error_m.mean, kM), number(s.relative_error_pct.mean, kPct),
                           number(s.time_us.mean, kUs), number(s.time_us.sd, kUs), text("")});
      },
      [](const PaperValues& p, std::vector<html::Cell>& r) {
        r.insert(r.end(), {text("1939"), number(p.mean_error_m, kM), number(p.error_variance, kM2),
                           number(p.error_sd_m, kM), text("n/a"), text("n/a"),
                           number(p.time_us, kUs), text("n/a"), number(p.time_per_pose_us, kUs)});
      });
  sec.table(std::move(t));
}

// The ten distance classes of every solver of the scope (Fig. 11's numbers
// and those beyond the paper).
void add_class_table(const ReportInput& in, const std::string& scope, Section& sec) {
  html::Table t{
      tid("classes", scope),
      "Ten distance classes (paper Fig. 11): distance error, reprojection and "
      "generalization error per class; jitter (pooled sd over the frames of a "
      "position) against bias (mean over positions of their mean error); "
      "efficiency = jitter² / (sigma_corner² · bound²), the bound for independent corner "
      "errors; below 1 that assumption fails (correlated corner errors), it is not a solver "
      "beating the bound",
      {"solver", "class (m)", "n", "mean error (m)", "variance (m²)", "sd (m)", "reprojection (px)",
       "generalization (px)", "positions", "jitter (m)", "bias (m)", "bias sd (m)", "efficiency"},
      {}};
  for (const SolverStudy& s : in.study.solvers) {
    if (s.scope != scope) continue;
    for (const DistanceClassStudy& c : s.classes) {
      t.rows.push_back({text(s.solver), text(class_range(c.lower_m, c.upper_m, 3)),
                        count(c.error_m.count), number(c.error_m.mean, kM),
                        number(c.error_m.variance, kM2), number(c.error_m.sd, kM),
                        number(c.reprojection_px.mean, kPx), number(c.generalization_px.mean, kPx),
                        count(c.positions), number(c.jitter_m, kM), number(c.bias_m, kM),
                        number(c.bias_sd_m, kM), number(c.efficiency)});
    }
  }
  sec.table(std::move(t));
}

// The full pose against the true pose per class (positions that recorded
// it): translation error per camera axis and rotation error.
void add_pose_table(const ReportInput& in, const std::string& scope, Section& sec) {
  html::Table t{
      tid("pose-errors", scope),
      "Pose errors per distance class against the true pose: t_est - t_true of T_cam_target "
      "along the camera's x (right), y (down) and z (optical axis), mean and sd; rotation error "
      "= angle of R_est^T R_true, degrees",
      {"solver", "class (m)", "n", "x mean (m)", "x sd (m)", "y mean (m)", "y sd (m)", "z mean (m)",
       "z sd (m)", "rotation mean (°)", "rotation sd (°)"},
      {}};
  for (const SolverStudy& s : in.study.solvers) {
    if (s.scope != scope) continue;
    for (const DistanceClassStudy& c : s.classes) {
      t.rows.push_back({text(s.solver), text(class_range(c.lower_m, c.upper_m, 3)),
                        count(c.rotation_error_deg.count), number(c.error_x_m.mean, kM),
                        number(c.error_x_m.sd, kM), number(c.error_y_m.mean, kM),
                        number(c.error_y_m.sd, kM), number(c.error_z_m.mean, kM),
                        number(c.error_z_m.sd, kM), number(c.rotation_error_deg.mean),
                        number(c.rotation_error_deg.sd)});
    }
  }
  sec.table(std::move(t));
}

void add_convergence_table(const ReportInput& in, Section& sec) {
  html::Table t{
      "convergence",
      "Convergence failures per solver: applicable estimates that did not converge, "
      "by termination reason; skipped = solver not applicable to the scope",
      {"solver", "scope", "run", "estimates", "skipped", "failed", "failure rate", "terminations"},
      {}};
  for (const SolverStudy& c : in.study.solvers) {
    for (const auto& [s, source] : with_baseline(in, c)) {
      std::string reasons;
      for (const auto& [why, n] : s->failures_by_termination)
        reasons += (reasons.empty() ? "" : "; ") + why + " " + std::to_string(n);
      t.rows.push_back({text(s->solver), text(s->scope), text(source), count(s->estimates),
                        count(s->skipped), count(s->failed),
                        number(fraction(s->failed, s->estimates - s->skipped), kRate),
                        text(reasons.empty() ? "-" : reasons)});
    }
  }
  sec.table(std::move(t));
}

void add_ambiguity_table(const ReportInput& in, Section& sec) {
  const ReportOptions& o = in.study.options;
  html::Table t{"ambiguity",
                "Planar ambiguity: converged estimates with ambiguity_ratio >= " +
                    num(o.ambiguity_ratio_threshold, 3) +
                    " (the worse planar solution within that factor of the better), and flips: "
                    "frames whose pose-marker rotation differs from the whole-target rotation "
                    "of the same solver by more than " +
                    num(o.flip_angle_deg, 3) + " degrees",
                {"solver", "scope", "run", "with ratio", "ambiguous", "rate", "frames compared",
                 "flips", "flip rate"},
                {}};
  for (const SolverStudy& c : in.study.solvers) {
    if (c.ambiguity_checked == 0 && c.flip_checked == 0) continue;
    for (const auto& [s, source] : with_baseline(in, c)) {
      t.rows.push_back({text(s->solver), text(s->scope), text(source), count(s->ambiguity_checked),
                        count(s->ambiguous),
                        number(fraction(s->ambiguous, s->ambiguity_checked), kRate),
                        count(s->flip_checked), count(s->flips),
                        number(fraction(s->flips, s->flip_checked), kRate)});
    }
  }
  sec.table(std::move(t));
}

void add_corner_noise_table(const RunStudy& st, Section& sec) {
  html::Table t{"corner-noise",
                "Corner noise per distance class: pooled within-position sd of each detected "
                "corner coordinate over the frames of a position (the sigma of the "
                "Cramér-Rao bound), px",
                {"class (m)", "sigma (px)", "degrees of freedom"},
                {}};
  for (const ClassCornerNoise& c : st.corner_noise) {
    t.rows.push_back(
        {text(class_range(c.lower_m, c.upper_m, 3)), number(c.sigma_px, kPx), count(c.dof)});
  }
  sec.table(std::move(t));
}

void add_detection_table(const RunStudy& st, Section& sec) {
  html::Table t{
      "detection",
      st.visible_markers_recorded
          ? "Detection against the marker's projected side at the true pose: rate = "
            "detected / (visible markers x frames); edge-fit residual (mean over "
            "markers and positions) and corner jitter (pooled within-position sd)"
          : "Detection rate not recorded (no visible markers in this run); corner "
            "quality against the detected side length",
      {"side (px)", "expected", "detected", "rate", "edge-fit residual (px)", "corner jitter (px)"},
      {}};
  for (const MarkerSizeClass& m : st.marker_sizes) {
    t.rows.push_back({text(class_range(m.lower_px, m.upper_px, 4)), count(m.expected),
                      count(m.detected), number(fraction(m.detected, m.expected), kRate),
                      number(m.edge_fit_residual_px.mean, kPx), number(m.corner_jitter_px, kPx)});
  }
  sec.table(std::move(t));
}

// What the misses behind the detection rate are: systematic (every frame
// of a position) or random, and where the systematic ones are.
void add_missed_markers(const RunStudy& st, Section& sec) {
  if (!st.visible_markers_recorded) return;
  if (st.missed_markers.empty()) {
    sec.paragraph("Every visible marker was detected in every frame of its position.");
    return;
  }
  std::size_t systematic = 0;
  std::string where;
  for (const MissedMarker& m : st.missed_markers) {
    if (m.frames_detected != 0) continue;
    ++systematic;
    if (systematic <= 12)
      where += (where.empty() ? "" : "; ") + std::string("marker ") + std::to_string(m.marker_id) +
               " at plan index " + std::to_string(m.plan_index) + " (" +
               fixed(m.true_distance_m, DisplayUnit{1e3, 1, "mm"}) + " mm, side " +
               fixed(m.side_px, DisplayUnit{1, 1, "px"}) + " px)";
  }
  std::string text = "Why the detection rate dips: " + std::to_string(st.missed_markers.size()) +
                     " (visible marker, position) pairs were missed in some frame; " +
                     std::to_string(systematic) +
                     " of them in every frame of their position (the marker could not be "
                     "detected there at all), the others in some frames only (random misses).";
  if (systematic > 0) {
    text += " Missed in every frame: " + where + (systematic > 12 ? "; ..." : "") +
            ". A marker counts as visible when its four corners project inside the image at the "
            "true pose; the detector also reads an intensity profile across each side and rejects "
            "a side whose profile leaves the image (DetectorStats::cut_by_image_border). At the "
            "closest positions, where every marker is large, the markers away from the pose "
            "marker can reach the image border: misses in every frame at the smallest distances "
            "are this field-of-view effect, not a failure to detect markers of that size, and "
            "make the rate of the largest size classes dip.";
  }
  sec.paragraph(text);
}

void add_stage_table(const ReportInput& in, Section& sec) {
  html::Table t{
      "stages",
      "Time per stage of a position, s",
      {"stage", "run", "n", "mean (s)", "sd (s)", "median (s)", "95th percentile (s)", "total (s)"},
      {}};
  auto rows = [&](const RunStudy& run, const std::string& source) {
    for (const StageStudy& s : run.stages) {
      t.rows.push_back({text(s.stage), text(source), count(s.seconds.count),
                        number(s.seconds.mean, kS), number(s.seconds.sd, kS),
                        number(s.median_s, kS), number(s.p95_s, kS),
                        number(s.seconds.mean * static_cast<double>(s.seconds.count), kS)});
    }
  };
  rows(in.study, "this run");
  if (in.baseline) rows(*in.baseline, "baseline");
  sec.table(std::move(t));
}

void add_event_table(const RunStudy& st, Section& sec) {
  html::Table t{"events",
                "Faults, pauses and resumes recorded during the sweep",
                {"at", "plan index", "kind", "message"},
                {}};
  for (const store::RunEvent& e : st.events) {
    t.rows.push_back({text(e.at), text(e.plan_index ? std::to_string(*e.plan_index) : "-"),
                      text(e.kind), text(e.message)});
  }
  if (t.rows.empty()) t.rows.push_back({text("-"), text("-"), text("none"), text("-")});
  sec.table(std::move(t));
}

}  // namespace

void add_paper_tables(const ReportInput& in, const std::string& scope, Section& sec) {
  add_image_error_table(in, scope, sec, "table2",
                        "Reconstruction (reprojection) error, px (paper Table 2)",
                        &SolverStudy::reprojection_px, &PaperValues::reprojection_mean_px,
                        &PaperValues::reprojection_variance, &PaperValues::reprojection_sd_px);
  if (scope != "target") {
    add_image_error_table(
        in, scope, sec, "table3",
        "Generalization error: RMS reprojection error of the other markers' corners "
        "with the pose marker's pose, px (paper Table 3)",
        &SolverStudy::generalization_px, &PaperValues::generalization_mean_px,
        &PaperValues::generalization_variance, &PaperValues::generalization_sd_px);
  }
  add_regression_table(in, scope, sec);
  add_residual_table(in, scope, sec);
  add_distance_table(in, scope, sec);
  add_class_table(in, scope, sec);
  if (in.study.true_poses_recorded) add_pose_table(in, scope, sec);
}

void add_beyond_tables(const ReportInput& in, Section& sec) {
  add_convergence_table(in, sec);
  add_ambiguity_table(in, sec);
  add_corner_noise_table(in.study, sec);
  add_detection_table(in.study, sec);
  add_missed_markers(in.study, sec);
  add_stage_table(in, sec);
  add_event_table(in.study, sec);
}

void add_detector_tables(const ReportInput& in, Section& sec) {
  const RunStudy& st = in.study;
  html::Table t{"detector-rates",
                "Detectors: markers in view found (each once per frame; in view = the whole "
                "outline 3 px inside the image at the true pose), RMS distance of their corners "
                "from the true corners (the layout projected through the run's camera at the "
                "true pose from the bench read-back and the rig geometry), px, over the "
                "detections within 10 px of it (misplaced: farther, an id decoded elsewhere), "
                "and mean detector time per frame. The truth is only as good as the run's "
                "camera calibration and rig geometry, whose errors enter every detector's RMS "
                "alike: compare the detectors with each other",
                {"detector", "found", "in view", "rate", "corner RMS vs truth (px)",
                 "detections with truth", "misplaced", "time per frame (s)"},
                {}};
  for (const DetectorStudy& d : st.detectors) {
    const double rate = d.views_in_view > 0 ? static_cast<double>(d.views_found) /
                                                  static_cast<double>(d.views_in_view)
                                            : kNaN;
    t.rows.push_back({text(d.detector + (d.primary ? " (primary)" : "")), count(d.views_found),
                      count(d.views_in_view), number(rate, kRate), number(d.corner_rms_px, kPx),
                      count(d.corners_vs_truth), count(d.misplaced),
                      number(d.time_per_frame_s, kS)});
  }
  sec.table(std::move(t));

  // The pose-marker scope: the first scope that is not "target".
  std::string scope;
  std::vector<std::string> solvers;  // the primary detector's series: the plain solver names
  for (const SolverStudy& s : st.solvers) {
    if (s.scope == "target") continue;
    if (scope.empty()) scope = s.scope;
    if (s.solver.find('@') == std::string::npos &&
        std::find(solvers.begin(), solvers.end(), s.solver) == solvers.end())
      solvers.push_back(s.solver);
  }
  if (scope.empty()) return;
  std::vector<std::string> columns{"detector"};
  for (const std::string& s : solvers)
    columns.push_back(s + " (m)");
  html::Table e{"detector-solver",
                "Mean |distance error| of each solver on each detector's corners, pose marker "
                "(scope \"" +
                    scope +
                    "\"), converged estimates; the full figures of each are "
                    "the summary rows SOLVER@DETECTOR",
                columns,
                {}};
  const std::string& primary = st.run.description.primary_detector;
  for (const DetectorStudy& d : st.detectors) {
    std::vector<html::Cell> row{text(d.detector)};
    for (const std::string& solver : solvers) {
      const SolverStudy* s = st.find(series_name(solver, d.detector, primary), scope);
      row.push_back(number(s && s->used > 0 ? s->abs_error_m.mean : kNaN, kM));
    }
    e.rows.push_back(std::move(row));
  }
  sec.table(std::move(e));
}

void add_comparison(const ReportInput& in, Section& sec) {
  std::size_t worse = 0, better = 0;
  for (const ComparedFigure& f : in.comparison) {
    worse += f.worse ? 1 : 0;
    better += f.better ? 1 : 0;
  }
  // The thresholds differ by figure (Student's t for means over few
  // positions); the page quotes the smallest, the normal one.
  double family_k = kNaN;
  for (const ComparedFigure& f : in.comparison)
    if (!(f.regression_k >= family_k)) family_k = f.regression_k;
  sec.paragraph(
      std::to_string(worse) + " figure(s) significantly worse and " + std::to_string(better) +
      " significantly better than the baseline. A difference is flagged (\"changed\") beyond " +
      num(in.study.options.significance_k, 3) +
      " standard errors; errors and failure rates count as worse or better beyond " +
      num(family_k, 3) +
      " standard errors (more for a mean over few positions, by Student's t: the table's z is "
      "then compared with the t quantile of the same tail), the same threshold raised by "
      "Bonferroni's correction for the number of counted figures, so that a run drawn from "
      "the baseline's distributions is called regressed no more often than a single comparison "
      "would be. Errors are compared as "
      "per-position means (frames of one position share its pose and are not independent); "
      "times, line parameters and class biases are flagged but never counted. Whole-run "
      "means depend on the distances visited: compare runs of the same plan.");
  if (in.baseline && !same_plan_of(in.study, *in.baseline)) {
    sec.paragraph(
        "The two runs ran different plans (their plan descriptions differ), so plan index i is "
        "not the same position in both: the per-position errors are compared by Welch's test on "
        "each run's per-position means, not paired position by position. Differences in the "
        "distances visited show up as differences of these means.");
  }
  html::Table t{"comparison",
                "Every compared figure: this run against the baseline",
                {"solver", "scope", "figure", "this run", "baseline", "difference",
                 "standard error", "z", "verdict"},
                {}};
  for (const ComparedFigure& f : in.comparison) {
    const std::string verdict = f.worse                    ? "worse"
                                : f.better                 ? "better"
                                : f.difference.significant ? (f.counted ? "changed (below the "
                                                                          "family-wise threshold)"
                                                                        : "changed")
                                                           : "no significant change";
    const std::string css = f.worse ? "worse" : f.better ? "better" : "";
    // Each row has its own unit: lengths in mm or µm by the row's values.
    const bool length = f.figure.find("(m)") != std::string::npos;
    const DisplayUnit u = display_unit(length ? kM : Quantity::kPlain,
                                       std::max({std::fabs(f.candidate), std::fabs(f.baseline),
                                                 std::fabs(f.difference.difference)}));
    std::string figure = f.figure;
    if (length) figure.replace(figure.find("(m)"), 3, "(" + u.symbol + ")");
    auto value = [&](double v) { return text(fixed(v, u), "num"); };
    t.rows.push_back({text(f.solver), text(f.scope), text(figure), value(f.candidate),
                      value(f.baseline), value(f.difference.difference),
                      value(f.difference.standard_error), number(f.difference.z),
                      text(verdict, css)});
  }
  sec.table(std::move(t));
}

}  // namespace db::report
