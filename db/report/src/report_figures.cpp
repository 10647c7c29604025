// The figures of the report: the paper's Figs. 8, 9, 11 and 12 per scope,
// and those of the statistics beyond the paper. With a baseline each series
// is drawn again, dashed, from the baseline's study.
#include <algorithm>
#include <cmath>
#include <functional>

#include "report_data.hpp"
#include "report_document.hpp"

namespace db::report {
namespace {

using ClassValue = std::function<double(const DistanceClassStudy&)>;

std::size_t solver_index(const RunStudy& study, const std::string& solver) {
  std::vector<std::string> names;
  for (const SolverStudy& s : study.solvers)
    if (std::find(names.begin(), names.end(), s.solver) == names.end()) names.push_back(s.solver);
  return static_cast<std::size_t>(std::find(names.begin(), names.end(), solver) - names.begin());
}

// A solver's own colour and marker, the same in every figure.
svg::Series& solver_style(const RunStudy& study, const std::string& solver, svg::Series& s) {
  const std::size_t index = solver_index(study, solver);
  s.colour = colour_of(index);
  s.marker = marker_of(index);
  return s;
}

double centre(const DistanceClassStudy& c) {
  return 0.5 * (c.lower_m + c.upper_m);
}

// The spread of a class's values (the band) and the confidence interval of
// its mean (the error bars).
struct ClassSpread {
  ClassValue band, ci;
};

// Half-width of the 95 % confidence interval of a mean of n independent
// values of standard deviation sd: t(0.975, n - 1) sd / sqrt(n); NaN for n < 2.
double ci95(double sd, std::size_t n) {
  if (n < 2 || !std::isfinite(sd)) return kNaN;
  const double dn = static_cast<double>(n);
  return stats::two_sided_threshold(0.05, dn - 1) * sd / std::sqrt(dn);
}

svg::Series class_series(const SolverStudy& s, const ClassValue& value, const ClassSpread& spread,
                         const std::string& label, const std::string& colour, bool dashed) {
  svg::Series out;
  out.label = label;
  out.style = svg::SeriesStyle::kLineAndMarkers;
  out.dashed = dashed;
  out.colour = colour;
  auto finite = [](double v) { return std::isfinite(v) ? v : kNaN; };
  for (const DistanceClassStudy& c : s.classes) {
    out.x.push_back(centre(c));
    out.y.push_back(value(c));
    if (spread.band) out.y_band.push_back(finite(spread.band(c)));
    if (spread.ci) out.y_error.push_back(finite(spread.ci(c)));
  }
  return out;
}

// One figure of a per-class figure of every solver of a scope (and the
// baseline's, dashed).
svg::Figure class_figure(const ReportInput& in, const std::string& scope, const std::string& id,
                         const std::string& title, svg::Axis y, const ClassValue& value,
                         const ClassSpread& error, const std::string& caption) {
  svg::Figure f;
  f.id = id;
  f.title = title;
  f.x = {"true distance", "m", false, 0.10, 1.00};
  f.y = std::move(y);
  f.caption = caption;
  f.width_px = 760;
  f.height_px = 440;
  for (const SolverStudy& s : in.study.solvers) {
    if (s.scope != scope || s.used == 0 || !s.coincides_with.empty()) continue;
    const std::string colour = colour_of(solver_index(in.study, s.solver));
    const std::string label = series_label(in.study, s);
    f.series.push_back(class_series(s, value, error, label, colour, false));
    solver_style(in.study, s.solver, f.series.back());
    if (in.baseline) {
      if (const SolverStudy* b = in.baseline->find(s.solver, scope)) {
        f.series.push_back(class_series(*b, value, error, label + " (baseline)", colour, true));
        solver_style(in.study, s.solver, f.series.back());
      }
    }
  }
  return f;
}

svg::Figure fit_figure(const ReportInput& in, const std::string& scope) {
  svg::Figure f;
  f.id = "fig12-" + scope;
  f.title = "Estimated against true distance, scope " + scope + " (paper Fig. 12)";
  f.x = {"true distance", "m", false, std::nullopt, std::nullopt};
  f.y = {"estimated distance", "m", false, std::nullopt, std::nullopt};
  f.caption = "Markers: each position's mean estimate (at most " +
              std::to_string(in.study.options.max_points_per_series) +
              " positions per solver drawn); lines: the least-squares fit over every estimate "
              "(dashed: the paper's fit from its Table 4 where it has one on this scale, and the "
              "baseline's fit).";
  f.width_px = 760;
  f.height_px = 520;
  for (const SolverStudy& s : in.study.solvers) {
    if (s.scope != scope || !s.ols || !s.coincides_with.empty()) continue;
    const std::string colour = colour_of(solver_index(in.study, s.solver));
    svg::Series points{series_label(in.study, s),
                       s.plot_true_m,
                       s.plot_estimated_m,
                       {},
                       svg::SeriesStyle::kMarkers,
                       false,
                       colour};
    f.series.push_back(solver_style(in.study, s.solver, points));
    // Iterators, not a structured binding: C++17 lets no lambda capture one
    // (gcc accepts it as an extension, clang refuses it).
    const auto true_range = std::minmax_element(s.plot_true_m.begin(), s.plot_true_m.end());
    const auto lo = true_range.first, hi = true_range.second;
    auto line = [&](const stats::LineFit& fit, bool dashed, const std::string& label) {
      svg::Series l;
      l.label = label;
      l.style = svg::SeriesStyle::kLine;
      l.dashed = dashed;
      l.colour = colour;
      for (double x : {*lo, *hi}) {
        l.x.push_back(x);
        l.y.push_back(fit.slope * x + fit.intercept);
      }
      return l;
    };
    f.series.push_back(line(*s.ols, false, ""));
    // The paper's own fit (Table 4), from its pose marker, beside ours.
    if (scope != "target") {
      const auto paper = paper_values(s.solver);
      // Only where it stays on the figure's scale: the paper's EKF fit
      // (a = 2.60, b = -1.10) would squash every other line flat.
      const auto on_scale = [&](double x) {
        const double y = paper->slope * x + paper->intercept_m;
        return y >= 0 && y <= 1.5 * *hi;
      };
      if (paper && on_scale(*lo) && on_scale(*hi)) {
        stats::LineFit fit;
        fit.slope = paper->slope;
        fit.intercept = paper->intercept_m;
        f.series.push_back(line(fit, true, s.solver + " (paper's fit, Table 4)"));
      }
    }
    if (in.baseline) {
      const SolverStudy* b = in.baseline->find(s.solver, scope);
      if (b != nullptr && b->ols)
        f.series.push_back(line(*b->ols, true, s.solver + " (baseline fit)"));
    }
  }
  return f;
}

// Fig. 12's points less the fitted line: what the full-range plot cannot show.
svg::Figure residual_figure(const ReportInput& in, const std::string& scope) {
  svg::Figure f;
  f.id = "fig12-residuals-" + scope;
  f.title = "Residuals of the fit, scope " + scope;
  f.x = {"true distance", "m", false, std::nullopt, std::nullopt};
  f.y = {"position's mean estimate - (a * true + b)", "m", false, std::nullopt, std::nullopt};
  f.caption =
      "The points of the figure above less each solver's least-squares line: curvature or a "
      "spread growing with distance shows here (dashed: the baseline's).";
  f.width_px = 760;
  f.height_px = 440;
  auto series = [](const SolverStudy& s, const std::string& label, const std::string& colour,
                   bool dashed) {
    svg::Series out{label, s.plot_true_m, {}, {}, svg::SeriesStyle::kMarkers, dashed, colour};
    for (std::size_t i = 0; i < s.plot_true_m.size(); ++i)
      out.y.push_back(s.plot_estimated_m[i] - (s.ols->slope * s.plot_true_m[i] + s.ols->intercept));
    return out;
  };
  for (const SolverStudy& s : in.study.solvers) {
    if (s.scope != scope || !s.ols || !s.coincides_with.empty()) continue;
    const std::string colour = colour_of(solver_index(in.study, s.solver));
    const std::string label = series_label(in.study, s);
    f.series.push_back(series(s, label, colour, false));
    solver_style(in.study, s.solver, f.series.back());
    if (in.baseline) {
      const SolverStudy* b = in.baseline->find(s.solver, scope);
      if (b != nullptr && b->ols) {
        f.series.push_back(series(*b, label + " (baseline)", colour, true));
        solver_style(in.study, s.solver, f.series.back());
      }
    }
  }
  return f;
}

// Variance over the Cramér-Rao bound per class, with the bound's corner
// noise measured from the frames (ClassCornerNoise). The bound is computed
// for corner errors independent between corners and coordinates; the
// database keeps neither the pose Jacobian nor the corners' error
// covariance, so the bound under correlated errors, (J^T S^-1 J)^-1, cannot
// be computed here. A ratio below 1 therefore says that assumption fails,
// never that a solver beat the bound: such a class is left out of the
// solver's own series and marked on the bound's line instead.
void add_efficiency_figure(const ReportInput& in, const std::string& scope, Section& sec) {
  svg::Figure f = class_figure(
      in, scope, "efficiency-" + scope, "Efficiency per class (scope " + scope + ")",
      {"variance / Cramér-Rao bound", "", true, std::nullopt, std::nullopt},
      [](const DistanceClassStudy& c) { return efficiency_drawn(c); }, {},
      "Frame-to-frame variance of the distance over sigma_corner² times the position's "
      "Cramér-Rao distance bound² (1 = efficient, the grey dashed line). Assumption: corner "
      "errors independent between corners and coordinates, with the sd sigma_corner measured "
      "in the class (pooled frame-to-frame sd of the detected corners, table \"corner-noise\"). "
      "No unbiased solver can go below the true bound, so a ratio below 1 means the assumption "
      "fails there (corners that share a fitted edge have correlated errors, and the solvers "
      "average less noise than sigma_corner suggests), not a solver better than the bound: "
      "such classes are not drawn as the solver's points but marked on the bound's line (grey "
      "open diamonds); their ratios are in the classes table and report.json "
      "(efficiency_below_bound).");
  svg::Series bound;
  bound.label = "Cramér-Rao bound (independent corner errors)";
  bound.style = svg::SeriesStyle::kLine;
  bound.colour = "#777777";
  bound.dashed = true;
  bound.x = {0.10, 1.00};
  bound.y = {1.0, 1.0};
  f.series.push_back(bound);
  svg::Series fails;
  fails.label = "a solver below 1 here: the assumption fails (see caption)";
  fails.style = svg::SeriesStyle::kMarkers;
  fails.colour = "#777777";
  fails.marker = 9;  // open diamond
  for (const SolverStudy& s : in.study.solvers) {
    if (s.scope != scope || s.used == 0 || !s.coincides_with.empty()) continue;
    for (const DistanceClassStudy& c : s.classes) {
      const double x = 0.5 * (c.lower_m + c.upper_m);
      if (efficiency_below_bound(c) &&
          std::find(fails.x.begin(), fails.x.end(), x) == fails.x.end()) {
        fails.x.push_back(x);
        fails.y.push_back(1.0);
      }
    }
  }
  std::sort(fails.x.begin(), fails.x.end());
  if (!fails.x.empty()) f.series.push_back(std::move(fails));
  sec.figure(std::move(f));
}

// The full pose against the true pose: the mean error per axis of the
// camera frame and the rotation error per class, bands ± 1 sd of the
// estimates (frames of one position share its pose, so no confidence
// interval over estimates is drawn).
void add_pose_figures(const ReportInput& in, const std::string& scope, Section& sec) {
  using Member = stats::Summary DistanceClassStudy::*;
  const std::string where = " (scope " + scope + ")";
  const struct {
    const char* axis;
    Member summary;
    const char* direction;
  } axes[] = {{"x", &DistanceClassStudy::error_x_m, "right in the image"},
              {"y", &DistanceClassStudy::error_y_m, "down in the image"},
              {"z", &DistanceClassStudy::error_z_m, "along the optical axis"}};
  for (const auto& a : axes) {
    const Member m = a.summary;
    sec.figure(class_figure(
        in, scope, std::string("pose-") + a.axis + "-" + scope,
        std::string("Translation error along camera ") + a.axis + " per class" + where,
        {std::string("estimated - true t_") + a.axis, "m", false, std::nullopt, std::nullopt},
        [m](const DistanceClassStudy& c) { return (c.*m).mean; },
        {[m](const DistanceClassStudy& c) { return (c.*m).sd; }, {}},
        std::string("Mean of t_est - t_true along the camera's ") + a.axis + " axis (" +
            a.direction +
            ") of T_cam_target, the target origin in the camera frame, against "
            "the true pose from the bench read-back and the rig geometry. Shaded band: ± 1 sd "
            "of the estimates."));
  }
  sec.figure(class_figure(
      in, scope, "pose-rotation-" + scope, "Rotation error per class" + where,
      {"angle of R_est^T R_true", "°", false, std::nullopt, std::nullopt},
      [](const DistanceClassStudy& c) { return c.rotation_error_deg.mean; },
      {[](const DistanceClassStudy& c) { return c.rotation_error_deg.sd; }, {}},
      "Mean rotation error: the angle of R_est^T R_true of T_cam_target, degrees. Shaded band: "
      "± 1 sd of the estimates."));
}

}  // namespace

void add_paper_figures(const ReportInput& in, const std::string& scope, Section& sec) {
  const std::string where = " (scope " + scope + ")";
  // Image errors: the band is the frames' sd; the mean's interval uses the
  // class's positions as the independent draws (frames of one position share
  // its pose), with the frames' sd, which is at least the sd of the
  // positions' means: a conservative interval.
  const ClassSpread reprojection{
      [](const DistanceClassStudy& c) { return c.reprojection_px.sd; },
      [](const DistanceClassStudy& c) { return ci95(c.reprojection_px.sd, c.positions); }};
  const ClassSpread generalization{
      [](const DistanceClassStudy& c) { return c.generalization_px.sd; },
      [](const DistanceClassStudy& c) { return ci95(c.generalization_px.sd, c.positions); }};
  // Distance error: the band is the frames' sd; the mean's interval is that
  // of the mean over positions of their mean error (bias_sd over positions).
  const ClassSpread distance{
      [](const DistanceClassStudy& c) { return c.error_m.sd; },
      [](const DistanceClassStudy& c) { return ci95(c.bias_sd_m, c.positions); }};
  const std::string bands =
      " Shaded band: ± 1 sd of the estimates; error bars: 95 % confidence interval of the mean "
      "(Student's t over the class's positions, the independent draws).";
  sec.figure(class_figure(
      in, scope, "fig8-" + scope, "Reconstruction error against distance" + where,
      {"reprojection error", "px", false, std::nullopt, std::nullopt},
      [](const DistanceClassStudy& c) { return c.reprojection_px.mean; }, reprojection,
      "Mean RMS reprojection error per distance class (paper Fig. 8)." + bands));
  if (scope != "target") {
    sec.figure(class_figure(
        in, scope, "fig9-" + scope, "Generalization error against distance" + where,
        {"generalization error", "px", false, std::nullopt, std::nullopt},
        [](const DistanceClassStudy& c) { return c.generalization_px.mean; }, generalization,
        "Mean RMS reprojection error of the other markers' corners with the pose marker's "
        "pose (paper Fig. 9)." +
            bands));
  }
  sec.figure(class_figure(
      in, scope, "fig11-mean-" + scope, "Mean distance error per class" + where,
      {"estimated - true distance", "m", false, std::nullopt, std::nullopt},
      [](const DistanceClassStudy& c) { return c.error_m.mean; }, distance,
      "Mean distance error in the ten distance classes (paper Fig. 11)." + bands));
  sec.figure(class_figure(
      in, scope, "fig11-variance-" + scope, "Variance of the distance error per class" + where,
      {"variance of the distance error", "m²", true, std::nullopt, std::nullopt},
      [](const DistanceClassStudy& c) { return c.error_m.variance; }, {},
      "Variance of the distance error in the ten distance classes (paper Fig. 11), log scale."));
  sec.figure(fit_figure(in, scope));
  sec.figure(residual_figure(in, scope));
  sec.figure(class_figure(
      in, scope, "jitter-" + scope, "Jitter per class" + where,
      {"jitter (sd over the frames of a position)", "m", true, std::nullopt, std::nullopt},
      [](const DistanceClassStudy& c) { return c.jitter_m; }, {},
      "Pooled standard deviation of the distance over the frames of one position: the "
      "noise part of the error, to compare with the bias below."));
  sec.figure(class_figure(
      in, scope, "bias-" + scope, "Bias per class" + where,
      {"bias (mean over positions of their mean error)", "m", false, std::nullopt, std::nullopt},
      [](const DistanceClassStudy& c) { return c.bias_m; },
      {[](const DistanceClassStudy& c) { return c.bias_sd_m; },
       [](const DistanceClassStudy& c) { return ci95(c.bias_sd_m, c.positions); }},
      "Mean over positions of (position's mean estimate - true distance): the systematic part "
      "of the error. Shaded band: ± 1 sd over positions; error bars: its 95 % confidence "
      "interval."));
  add_efficiency_figure(in, scope, sec);
  if (in.study.true_poses_recorded) add_pose_figures(in, scope, sec);
}

namespace {

// Rate of ambiguous estimates (ambiguity) or flips (!ambiguity) of a solver
// and scope, per distance or viewing-angle class.
svg::Series rate_series(const SolverStudy& s, bool ambiguity, bool by_angle,
                        const std::string& label, const std::string& colour, bool dashed) {
  svg::Series out{label, {}, {}, {}, svg::SeriesStyle::kLineAndMarkers, dashed, colour};
  auto add = [&](double x, std::size_t ac, std::size_t a, std::size_t fc, std::size_t fl) {
    out.x.push_back(x);
    out.y.push_back(ambiguity ? fraction(a, ac) : fraction(fl, fc));
  };
  if (by_angle) {
    for (const AngleClassStudy& c : s.by_viewing_angle)
      add(0.5 * (c.lower_deg + c.upper_deg), c.ambiguity_checked, c.ambiguous, c.flip_checked,
          c.flips);
  } else {
    for (const DistanceClassStudy& c : s.classes)
      add(centre(c), c.ambiguity_checked, c.ambiguous, c.flip_checked, c.flips);
  }
  return out;
}

void add_rate_figures(const ReportInput& in, Section& sec) {
  const RunStudy& st = in.study;
  for (const bool ambiguity : {true, false}) {
    for (const bool by_angle : {false, true}) {
      if (by_angle && !st.viewing_angles_recorded) continue;
      svg::Figure f;
      f.id = std::string(ambiguity ? "ambiguity-" : "flips-") + (by_angle ? "angle" : "distance");
      f.title = std::string(ambiguity ? "Planar ambiguity" : "Flips") + " against " +
                (by_angle ? "viewing angle" : "distance");
      f.x = by_angle ? svg::Axis{"viewing angle at the true pose", "deg", false, 0.0, 90.0}
                     : svg::Axis{"true distance", "m", false, 0.10, 1.00};
      f.y = {ambiguity ? "ambiguous / estimates with a ratio" : "flips / frames with both scopes",
             "", false, 0.0, std::nullopt};
      f.caption =
          ambiguity
              ? "Converged estimates whose ambiguity_ratio (better over worse planar solution's "
                "error) is at least " +
                    num(st.options.ambiguity_ratio_threshold, 3) +
                    ", of the converged estimates with a ratio."
              : "Frames whose pose-marker rotation differs from the whole-target rotation of the "
                "same solver by more than " +
                    num(st.options.flip_angle_deg, 3) + " degrees.";
      f.caption += " Solvers with none are in the ambiguity table only; dashed: the baseline.";
      f.width_px = 760;
      f.height_px = 420;
      for (const SolverStudy& s : st.solvers) {
        const std::size_t events = ambiguity ? s.ambiguous : s.flips;
        const SolverStudy* b = in.baseline ? in.baseline->find(s.solver, s.scope) : nullptr;
        const std::size_t baseline_events = b == nullptr ? 0 : ambiguity ? b->ambiguous : b->flips;
        if (events == 0 && baseline_events == 0) continue;
        if (!s.coincides_with.empty()) continue;
        const std::string colour = colour_of(solver_index(st, s.solver));
        const std::string label = series_label(st, s) + (ambiguity ? " (" + s.scope + ")" : "");
        f.series.push_back(rate_series(s, ambiguity, by_angle, label, colour, false));
        solver_style(st, s.solver, f.series.back());
        if (b != nullptr) {
          f.series.push_back(
              rate_series(*b, ambiguity, by_angle, label + " (baseline)", colour, true));
          solver_style(st, s.solver, f.series.back());
        }
      }
      sec.figure(std::move(f));
    }
  }
}

// Detection rate, edge-fit residual and corner jitter per marker-size class.
void size_series(const RunStudy& st, const std::string& suffix, bool dashed, svg::Series& rate,
                 svg::Series& edge, svg::Series& jitter) {
  rate = {"detection rate" + suffix,         {},     {},          {},
          svg::SeriesStyle::kLineAndMarkers, dashed, colour_of(0)};
  edge = {"edge-fit residual" + suffix,      {},     {},          {},
          svg::SeriesStyle::kLineAndMarkers, dashed, colour_of(1)};
  jitter = {"corner jitter" + suffix,          {},     {},          {},
            svg::SeriesStyle::kLineAndMarkers, dashed, colour_of(2)};
  for (const MarkerSizeClass& m : st.marker_sizes) {
    const double x = 0.5 * (m.lower_px + m.upper_px);
    rate.x.push_back(x);
    rate.y.push_back(fraction(m.detected, m.expected));
    edge.x.push_back(x);
    edge.y.push_back(m.edge_fit_residual_px.mean);
    jitter.x.push_back(x);
    jitter.y.push_back(m.corner_jitter_px);
  }
}

}  // namespace

void add_beyond_figures(const ReportInput& in, Section& sec) {
  const RunStudy& st = in.study;
  add_rate_figures(in, sec);
  if (st.marker_sizes.empty()) return;
  svg::Figure rate;
  rate.id = "detection-rate";
  rate.title = "Detection rate against marker size";
  rate.x = {"projected marker side at the true pose", "px", false, std::nullopt, std::nullopt};
  rate.y = {"detected / visible", "", false, 0.0, 1.05};
  rate.caption =
      "Fraction of (visible marker, frame) pairs in which the marker was detected; dashed: the "
      "baseline.";
  svg::Figure quality;
  quality.id = "corner-quality";
  quality.title = "Corner quality against marker size";
  quality.x = rate.x;
  quality.y = {"edge-fit residual, corner jitter", "px", true, std::nullopt, std::nullopt};
  quality.caption =
      "Edge-fit residual (RMS of edge samples about the fitted sides, mean over markers and "
      "positions) and corner jitter (pooled frame-to-frame sd of the corners), per marker-size "
      "class; dashed: the baseline.";
  svg::Series r, edge, jitter;
  size_series(st, "", false, r, edge, jitter);
  rate.series.push_back(r);
  quality.series = {edge, jitter};
  if (in.baseline && !in.baseline->marker_sizes.empty()) {
    size_series(*in.baseline, " (baseline)", true, r, edge, jitter);
    if (in.baseline->visible_markers_recorded) rate.series.push_back(r);
    quality.series.push_back(edge);
    quality.series.push_back(jitter);
  }
  if (st.visible_markers_recorded) sec.figure(std::move(rate));
  sec.figure(std::move(quality));
}

}  // namespace db::report
