#include "report_study.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "db/stats/eiv.hpp"
#include "db/stats/error.hpp"
#include "db/stats/regression.hpp"

namespace db::report {

stats::EqualWidthBins distance_classes() {
  return stats::EqualWidthBins(0.10, 1.00, 10);
}

std::optional<std::size_t> distance_class(const stats::EqualWidthBins& bins, double d) {
  if (d < bins.lower() && d >= bins.lower() - kClassEdgeToleranceM) return 0;
  if (d > bins.upper() && d <= bins.upper() + kClassEdgeToleranceM) return bins.count() - 1;
  return bins.index_of(d);
}

stats::EqualWidthBins viewing_angle_classes() {
  return stats::EqualWidthBins(0.0, 90.0, 9);
}

namespace {

// Pooled within-group variance: sum (n-1) s^2 / sum (n-1).
struct Pooled {
  double sum_squares = 0;
  double dof = 0;
  void add(const stats::Summary& s) {
    if (s.count < 2) return;
    sum_squares += s.variance * static_cast<double>(s.count - 1);
    dof += static_cast<double>(s.count - 1);
  }
  double variance() const { return dof > 0 ? sum_squares / dof : kNaN; }
  double sd() const { return std::sqrt(variance()); }
};

// One position's used estimates of one solver and scope.
struct PositionGroup {
  std::uint32_t position = 0;
  stats::RunningSummary distance, abs_error, reprojection, generalization;
};

// Accumulators of one distance class.
struct ClassAccumulator {
  stats::RunningSummary error, reprojection, generalization, bias;
  Pooled jitter;
  double bound_sum_squares = 0;  // sum (n_p - 1) sigma^2 b_p^2
  double bound_dof = 0;          // dof of the positions that have a bound
  double jitter_with_bound = 0;  // sum (n_p - 1) s_p^2 over those positions
};

std::optional<double> bound_of(const store::PositionRecord& p, const std::string& scope) {
  for (const store::DistanceBound& b : p.distance_bounds) {
    if (b.scope == scope) return b.distance_sd_m_per_px;
  }
  return std::nullopt;
}

template <class Class>
void count_ambiguity(Class& c, bool ambiguous) {
  ++c.ambiguity_checked;
  c.ambiguous += ambiguous ? 1 : 0;
}

template <class Class>
void count_flip(Class& c, bool flip) {
  ++c.flip_checked;
  c.flips += flip ? 1 : 0;
}

std::vector<ClassCornerNoise> corner_noise_by_class(const RunData& data) {
  const stats::EqualWidthBins bins = distance_classes();
  std::vector<Pooled> pooled(bins.count());
  for (const PositionData& p : data.positions) {
    if (!p.record.true_distance_m) continue;
    const auto c = distance_class(bins, *p.record.true_distance_m);
    if (!c) continue;
    for (const MarkerAtPosition& m : p.markers) {
      pooled[*c].sum_squares += m.corner_sum_squares;
      pooled[*c].dof += static_cast<double>(m.corner_dof);
    }
  }
  std::vector<ClassCornerNoise> out;
  for (std::size_t i = 0; i < bins.count(); ++i) {
    out.push_back(
        {bins.edge(i), bins.edge(i + 1), pooled[i].sd(), static_cast<std::size_t>(pooled[i].dof)});
  }
  return out;
}

// The line fits of Tables 4-5 and the Deming line beside them; nullopt when
// the data define no line (fewer than 3 points, one distance only).
void fit_lines(const std::vector<double>& x, const std::vector<double>& y, double jitter_m,
               const ReportOptions& options, SolverStudy& s) {
  try {
    s.ols = stats::fit_line(x, y);
  } catch (const stats::StatsError&) {
    return;
  }
  // var(y error): the frame-to-frame jitter when positions have several
  // frames, else the OLS residual variance (which also holds the x error and
  // any misfit, so delta is then an upper estimate).
  const double var_y =
      std::isfinite(jitter_m) && jitter_m > 0 ? jitter_m * jitter_m : s.ols->residual_variance;
  const double var_x = options.true_distance_sd_m * options.true_distance_sd_m;
  if (!(var_y > 0) || !(var_x > 0)) return;
  s.deming_delta = var_y / var_x;
  try {
    s.deming = stats::fit_deming(x, y, s.deming_delta);
  } catch (const stats::StatsError&) {
    s.deming.reset();
  }
}

SolverStudy study_solver(const RunData& data, const SolverScopeData& rows,
                         const std::vector<ClassCornerNoise>& corner_noise,
                         const ReportOptions& options) {
  const stats::EqualWidthBins bins = distance_classes();
  const stats::EqualWidthBins angles = viewing_angle_classes();
  SolverStudy s;
  s.solver = rows.solver;
  s.scope = rows.scope;
  s.estimates = rows.samples.size();
  s.failures_by_termination = rows.failures_by_termination;
  for (std::size_t i = 0; i < bins.count(); ++i) {
    DistanceClassStudy c;
    c.lower_m = bins.edge(i);
    c.upper_m = bins.edge(i + 1);
    s.classes.push_back(c);
  }
  for (std::size_t i = 0; i < angles.count(); ++i) {
    AngleClassStudy a;
    a.lower_deg = angles.edge(i);
    a.upper_deg = angles.edge(i + 1);
    s.by_viewing_angle.push_back(a);
  }
  auto classes_of = [&](std::uint32_t position) {
    const store::PositionRecord& p = data.positions[position].record;
    return std::make_pair(
        p.true_distance_m ? distance_class(bins, *p.true_distance_m) : std::nullopt,
        p.true_viewing_angle_deg ? angles.index_of(*p.true_viewing_angle_deg) : std::nullopt);
  };

  stats::RunningSummary reprojection, generalization, error, abs_error, relative, time;
  std::vector<ClassAccumulator> acc(bins.count());
  std::vector<double> x, y;
  std::vector<PositionGroup> groups;
  for (const EstimateSample& e : rows.samples) {
    if (e.status == SampleStatus::kSkipped) {
      ++s.skipped;
      continue;
    }
    if (!std::isnan(e.time_us)) time.add(e.time_us);
    const auto [distance_class, angle_class] = classes_of(e.position);
    if (e.status == SampleStatus::kFailed) {
      ++s.failed;
      continue;
    }
    // Ambiguity of converged estimates only: a failed estimate's ratio
    // compares two solutions that did not converge.
    if (!std::isnan(e.ambiguity_ratio)) {
      const bool ambiguous = e.ambiguity_ratio >= options.ambiguity_ratio_threshold;
      count_ambiguity(s, ambiguous);
      if (distance_class) count_ambiguity(s.classes[*distance_class], ambiguous);
      if (angle_class) count_ambiguity(s.by_viewing_angle[*angle_class], ambiguous);
    }
    const store::PositionRecord& p = data.positions[e.position].record;
    // An unknown (or impossible) true distance: the estimate converged but
    // there is nothing to compare it with.
    if (!p.true_distance_m || !std::isfinite(*p.true_distance_m) || *p.true_distance_m <= 0) {
      continue;
    }
    ++s.used;
    const double truth = *p.true_distance_m;
    const double err = e.distance_m - truth;
    const bool has_generalization = !std::isnan(e.generalization_px);
    reprojection.add(e.reprojection_px);
    if (has_generalization) generalization.add(e.generalization_px);
    error.add(err);
    abs_error.add(std::fabs(err));
    relative.add(100.0 * std::fabs(err) / truth);
    x.push_back(truth);
    y.push_back(e.distance_m);
    if (groups.empty() || groups.back().position != e.position) {
      groups.push_back(PositionGroup{e.position, {}, {}, {}, {}});
    }
    PositionGroup& g = groups.back();
    g.distance.add(e.distance_m);
    g.abs_error.add(std::fabs(err));
    g.reprojection.add(e.reprojection_px);
    if (has_generalization) g.generalization.add(e.generalization_px);
    if (distance_class) {
      ClassAccumulator& a = acc[*distance_class];
      a.error.add(err);
      a.reprojection.add(e.reprojection_px);
      if (has_generalization) a.generalization.add(e.generalization_px);
    }
  }

  // Per position: jitter, bias, efficiency, the per-position means run
  // comparison tests, and the points of Fig. 12.
  Pooled jitter_all;
  stats::RunningSummary position_abs, position_reprojection, position_generalization;
  const std::size_t stride =
      std::max<std::size_t>(1, (groups.size() + options.max_points_per_series - 1) /
                                   std::max<std::size_t>(1, options.max_points_per_series));
  for (std::size_t i = 0; i < groups.size(); ++i) {
    const PositionGroup& g = groups[i];
    const store::PositionRecord& p = data.positions[g.position].record;
    const stats::Summary d = g.distance.summary();
    position_abs.add(g.abs_error.summary().mean);
    position_reprojection.add(g.reprojection.summary().mean);
    const stats::Summary gen = g.generalization.summary();
    if (gen.count > 0) position_generalization.add(gen.mean);
    s.per_position.push_back({p.plan_index, g.abs_error.summary().mean,
                              g.reprojection.summary().mean, gen.count > 0 ? gen.mean : kNaN});
    jitter_all.add(d);
    if (i % stride == 0) {
      s.plot_true_m.push_back(*p.true_distance_m);
      s.plot_estimated_m.push_back(d.mean);
    }
    const auto c = distance_class(bins, *p.true_distance_m);
    if (!c) continue;
    ClassAccumulator& a = acc[*c];
    a.bias.add(d.mean - *p.true_distance_m);
    a.jitter.add(d);
    const auto bound = bound_of(p, s.scope);
    const double sigma = corner_noise[*c].sigma_px;
    if (bound && d.count >= 2 && std::isfinite(sigma)) {
      const double n1 = static_cast<double>(d.count - 1);
      a.bound_sum_squares += n1 * sigma * sigma * *bound * *bound;
      a.bound_dof += n1;
      a.jitter_with_bound += n1 * d.variance;
    }
  }
  for (std::size_t i = 0; i < bins.count(); ++i) {
    DistanceClassStudy& c = s.classes[i];
    const ClassAccumulator& a = acc[i];
    c.error_m = a.error.summary();
    c.reprojection_px = a.reprojection.summary();
    c.generalization_px = a.generalization.summary();
    const stats::Summary bias = a.bias.summary();
    c.positions = bias.count;
    c.bias_m = bias.mean;
    c.bias_sd_m = bias.sd;
    c.jitter_m = a.jitter.sd();
    c.efficiency = a.bound_sum_squares > 0 ? a.jitter_with_bound / a.bound_sum_squares : kNaN;
  }

  // Flips: the pose marker's rotation against the whole target's, per frame.
  if (s.scope != "target") {
    const auto it = data.flips.find(s.solver);
    if (it != data.flips.end()) {
      for (const FlipSample& f : it->second) {
        const bool flip = f.angle_deg > options.flip_angle_deg;
        const auto [distance_class, angle_class] = classes_of(f.position);
        count_flip(s, flip);
        if (distance_class) count_flip(s.classes[*distance_class], flip);
        if (angle_class) count_flip(s.by_viewing_angle[*angle_class], flip);
      }
    }
  }

  s.reprojection_px = reprojection.summary();
  s.generalization_px = generalization.summary();
  s.error_m = error.summary();
  s.abs_error_m = abs_error.summary();
  s.relative_error_pct = relative.summary();
  s.time_us = time.summary();
  s.position_abs_error_m = position_abs.summary();
  s.position_reprojection_px = position_reprojection.summary();
  s.position_generalization_px = position_generalization.summary();
  fit_lines(x, y, jitter_all.sd(), options, s);
  return s;
}

std::vector<StageStudy> study_stages(const RunData& data) {
  std::map<std::string, std::vector<double>> by_stage;
  for (const PositionData& p : data.positions) {
    for (const store::StageTime& t : p.record.stage_times) {
      if (std::isfinite(t.seconds)) by_stage[t.stage].push_back(t.seconds);
    }
  }
  std::vector<StageStudy> out;
  for (auto& [stage, seconds] : by_stage) {
    StageStudy st;
    st.stage = stage;
    st.seconds = stats::summarize(seconds);
    const std::vector<double> q = stats::quantiles(seconds, {0.5, 0.95});
    st.median_s = q[0];
    st.p95_s = q[1];
    out.push_back(st);
  }
  return out;
}

// Detection rate and corner quality against the marker's side length in px.
// Visible markers with a non-finite side are left out and counted in
// nonfinite_sides.
std::vector<MarkerSizeClass> study_marker_sizes(const RunData& data, bool visible_recorded,
                                                std::size_t& nonfinite_sides) {
  // (side px, expected frames, marker at position or nullptr)
  struct Item {
    double side_px;
    std::size_t expected;
    const MarkerAtPosition* detected;
  };
  std::vector<Item> items;
  for (const PositionData& p : data.positions) {
    auto find = [&](int id) -> const MarkerAtPosition* {
      for (const MarkerAtPosition& m : p.markers)
        if (m.marker_id == id) return &m;
      return nullptr;
    };
    if (visible_recorded) {
      for (const store::VisibleMarker& v : p.record.visible_markers) {
        if (!std::isfinite(v.side_px)) {
          ++nonfinite_sides;
          continue;
        }
        items.push_back({v.side_px, p.frames, find(v.marker_id)});
      }
    } else {
      for (const MarkerAtPosition& m : p.markers) {
        if (std::isfinite(m.side_px)) items.push_back({m.side_px, 0, &m});
      }
    }
  }
  if (items.empty()) return {};
  double lo = items.front().side_px, hi = lo;
  for (const Item& i : items) {
    lo = std::min(lo, i.side_px);
    hi = std::max(hi, i.side_px);
  }
  lo = std::floor(lo);
  hi = std::max(std::ceil(hi), lo + 1.0);
  const stats::EqualWidthBins bins(lo, hi, 10);
  std::vector<MarkerSizeClass> out(bins.count());
  std::vector<stats::RunningSummary> edge(bins.count());
  std::vector<Pooled> jitter(bins.count());
  for (std::size_t i = 0; i < bins.count(); ++i) {
    out[i].lower_px = bins.edge(i);
    out[i].upper_px = bins.edge(i + 1);
  }
  for (const Item& i : items) {
    const auto c = bins.index_of(i.side_px);
    if (!c) continue;
    out[*c].expected += i.expected;
    if (i.detected == nullptr) continue;
    out[*c].detected += std::min(i.detected->frames_detected,
                                 visible_recorded ? i.expected : i.detected->frames_detected);
    if (i.detected->edge_fit_residual_px.count > 0)
      edge[*c].add(i.detected->edge_fit_residual_px.mean);
    jitter[*c].sum_squares += i.detected->corner_sum_squares;
    jitter[*c].dof += static_cast<double>(i.detected->corner_dof);
  }
  for (std::size_t i = 0; i < bins.count(); ++i) {
    out[i].edge_fit_residual_px = edge[i].summary();
    out[i].corner_jitter_px = jitter[i].sd();
  }
  return out;
}

}  // namespace

RunStudy compute_study(const RunData& data, const ReportOptions& options) {
  RunStudy study;
  study.database = data.database;
  study.run = data.run;
  study.options = options;
  study.events = data.events;
  study.positions = data.positions.size();
  for (const PositionData& p : data.positions) {
    study.failed_positions += p.record.status == store::PositionStatus::kFailed ? 1 : 0;
    study.frames += p.frames;
    study.visible_markers_recorded |= !p.record.visible_markers.empty();
    study.distance_bounds_recorded |= !p.record.distance_bounds.empty();
    study.viewing_angles_recorded |= p.record.true_viewing_angle_deg.has_value();
  }
  const stats::EqualWidthBins bins = distance_classes();
  for (const PositionData& p : data.positions) {
    if (p.record.status == store::PositionStatus::kOk &&
        (!p.record.true_distance_m || !distance_class(bins, *p.record.true_distance_m))) {
      ++study.positions_outside_classes;
    }
  }
  study.corner_noise = corner_noise_by_class(data);
  for (const SolverScopeData& rows : data.solvers) {
    study.estimates += rows.samples.size();
    study.solvers.push_back(study_solver(data, rows, study.corner_noise, options));
  }
  study.stages = study_stages(data);
  study.nonfinite_detections = data.nonfinite_detections;
  study.marker_sizes =
      study_marker_sizes(data, study.visible_markers_recorded, study.nonfinite_visible_markers);
  return study;
}

}  // namespace db::report
