#include "report_study.hpp"

#include <algorithm>
#include <cmath>
#include <future>
#include <map>
#include <utility>

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
  // A marker's corner coordinates over the frames of its position.
  void add_corners(const MarkerAtPosition& m) {
    sum_squares += m.corner_sum_squares;
    dof += static_cast<double>(m.corner_dof);
  }
  double variance() const { return dof > 0 ? sum_squares / dof : kNaN; }
  double sd() const { return std::sqrt(variance()); }
};

// One empty class per bin, with the bin's edges.
template <class Class>
std::vector<Class> empty_classes(const stats::EqualWidthBins& bins, double Class::*lower,
                                 double Class::*upper) {
  std::vector<Class> out(bins.count());
  for (std::size_t i = 0; i < bins.count(); ++i) {
    out[i].*lower = bins.edge(i);
    out[i].*upper = bins.edge(i + 1);
  }
  return out;
}

// The distance and viewing-angle classes a position falls in (nullopt:
// unknown or outside the classes).
struct PositionClasses {
  stats::EqualWidthBins distance = distance_classes();
  stats::EqualWidthBins angle = viewing_angle_classes();
  std::pair<std::optional<std::size_t>, std::optional<std::size_t>> of(
      const store::PositionRecord& p) const {
    return std::make_pair(
        p.true_distance_m ? distance_class(distance, *p.true_distance_m) : std::nullopt,
        p.true_viewing_angle_deg ? angle.index_of(*p.true_viewing_angle_deg) : std::nullopt);
  }
};

// One position's used estimates of one solver and scope.
struct PositionGroup {
  std::uint32_t position = 0;
  std::optional<std::size_t> distance_class;
  stats::RunningSummary distance, abs_error, reprojection, generalization;
};

// Accumulators of one distance class.
struct ClassAccumulator {
  stats::RunningSummary error, reprojection, generalization, bias;
  stats::RunningSummary error_x, error_y, error_z, rotation_error;  // against the true pose
  Pooled jitter;
  double bound_sum_squares = 0;  // sum (n_p - 1) sigma^2 b_p^2
  double bound_dof = 0;          // dof of the positions that have a bound
  double jitter_with_bound = 0;  // sum (n_p - 1) s_p^2 over those positions
};

// Everything one solver and scope accumulates over its estimates.
struct SolverAccumulator {
  stats::RunningSummary reprojection, generalization, error, abs_error, relative, time;
  std::vector<ClassAccumulator> classes = std::vector<ClassAccumulator>(distance_classes().count());
  std::vector<double> x, y;           // true and estimated distance of every used estimate, m
  std::vector<PositionGroup> groups;  // the positions with used estimates, by plan index
  // Over positions: each one's mean |error|, reprojection and generalization
  // error; and the spread of the distance within a position, pooled (the
  // y error of the Deming fit).
  stats::RunningSummary position_abs, position_reprojection, position_generalization;
  Pooled jitter;
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
    for (const MarkerAtPosition& m : p.markers)
      pooled[*c].add_corners(m);
  }
  std::vector<ClassCornerNoise> out =
      empty_classes(bins, &ClassCornerNoise::lower_m, &ClassCornerNoise::upper_m);
  for (std::size_t i = 0; i < bins.count(); ++i) {
    out[i].sigma_px = pooled[i].sd();
    out[i].dof = static_cast<std::size_t>(pooled[i].dof);
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

// The study's name, counts and empty classes, before any estimate is added.
SolverStudy empty_study(const SolverScopeData& rows, const PositionClasses& classes) {
  SolverStudy s;
  s.solver = rows.solver;
  s.scope = rows.scope;
  s.estimates = rows.samples.size();
  s.failures_by_termination = rows.failures_by_termination;
  s.classes =
      empty_classes(classes.distance, &DistanceClassStudy::lower_m, &DistanceClassStudy::upper_m);
  s.by_viewing_angle =
      empty_classes(classes.angle, &AngleClassStudy::lower_deg, &AngleClassStudy::upper_deg);
  return s;
}

// A converged estimate with a known true distance: into the whole-run
// figures, the fit's points, its position's group and its distance class.
void add_used_estimate(const EstimateSample& e, double truth,
                       std::optional<std::size_t> distance_class, SolverAccumulator& acc) {
  const double err = e.distance_m - truth;
  const bool has_generalization = !std::isnan(e.generalization_px);
  acc.reprojection.add(e.reprojection_px);
  if (has_generalization) acc.generalization.add(e.generalization_px);
  acc.error.add(err);
  acc.abs_error.add(std::fabs(err));
  acc.relative.add(100.0 * std::fabs(err) / truth);
  acc.x.push_back(truth);
  acc.y.push_back(e.distance_m);
  if (acc.groups.empty() || acc.groups.back().position != e.position) {
    acc.groups.push_back(PositionGroup{e.position, distance_class, {}, {}, {}, {}});
  }
  PositionGroup& g = acc.groups.back();
  g.distance.add(e.distance_m);
  g.abs_error.add(std::fabs(err));
  g.reprojection.add(e.reprojection_px);
  if (has_generalization) g.generalization.add(e.generalization_px);
  if (distance_class) {
    ClassAccumulator& a = acc.classes[*distance_class];
    a.error.add(err);
    a.reprojection.add(e.reprojection_px);
    if (has_generalization) a.generalization.add(e.generalization_px);
    if (!std::isnan(e.rotation_error_deg)) {
      a.error_x.add(e.error_x_m);
      a.error_y.add(e.error_y_m);
      a.error_z.add(e.error_z_m);
      a.rotation_error.add(e.rotation_error_deg);
    }
  }
}

// 95th percentile of |estimated - true| over the used estimates; NaN if none.
double abs_error_p95(const std::vector<double>& truth, const std::vector<double>& estimated) {
  if (truth.empty()) return kNaN;
  std::vector<double> abs_error(truth.size());
  for (std::size_t i = 0; i < truth.size(); ++i)
    abs_error[i] = std::fabs(estimated[i] - truth[i]);
  return stats::quantile(std::move(abs_error), 0.95);
}

// Half-width of the 95 % confidence interval of a mean over independent
// values: t(0.975, n - 1) * sd / sqrt(n); NaN below two values.
double mean_ci95(const stats::Summary& s) {
  if (s.count < 2 || !std::isfinite(s.sd)) return kNaN;
  const double n = static_cast<double>(s.count);
  return stats::two_sided_threshold(0.05, n - 1) * s.sd / std::sqrt(n);
}

// Every estimate of the solver and scope: skipped, failed and used counts,
// times, ambiguity, and the used estimates' accumulators.
void add_estimates(const RunData& data, const SolverScopeData& rows, const PositionClasses& classes,
                   const ReportOptions& options, SolverStudy& s, SolverAccumulator& acc) {
  for (const EstimateSample& e : rows.samples) {
    if (e.status == SampleStatus::kSkipped) {
      ++s.skipped;
      continue;
    }
    if (!std::isnan(e.time_us)) acc.time.add(e.time_us);
    if (e.status == SampleStatus::kFailed) {
      ++s.failed;
      continue;
    }
    const store::PositionRecord& p = data.positions[e.position].record;
    const auto [distance_class, angle_class] = classes.of(p);
    // Ambiguity of converged estimates only: a failed estimate's ratio
    // compares two solutions that did not converge.
    if (!std::isnan(e.ambiguity_ratio)) {
      const bool ambiguous = e.ambiguity_ratio >= options.ambiguity_ratio_threshold;
      count_ambiguity(s, ambiguous);
      if (distance_class) count_ambiguity(s.classes[*distance_class], ambiguous);
      if (angle_class) count_ambiguity(s.by_viewing_angle[*angle_class], ambiguous);
    }
    // An unknown (or impossible) true distance: the estimate converged but
    // there is nothing to compare it with.
    if (!p.true_distance_m || !std::isfinite(*p.true_distance_m) || *p.true_distance_m <= 0) {
      continue;
    }
    ++s.used;
    add_used_estimate(e, *p.true_distance_m, distance_class, acc);
    const double abs_error = std::fabs(e.distance_m - *p.true_distance_m);
    if (s.worst_plan_index < 0 || abs_error > s.worst_abs_error_m) {
      s.worst_plan_index = p.plan_index;
      s.worst_frame_index = static_cast<int>(e.frame);
      s.worst_abs_error_m = abs_error;
    }
  }
}

// One position's distances d (its used estimates, m) into its class: bias,
// jitter and, where the position has a Cramér-Rao bound (m/px) and the class
// a corner noise (px), the efficiency sums.
void add_position_to_class(const stats::Summary& d, double truth, std::optional<double> bound,
                           double sigma_px, ClassAccumulator& a) {
  a.bias.add(d.mean - truth);
  a.jitter.add(d);
  if (bound && d.count >= 2 && std::isfinite(sigma_px)) {
    const double n1 = static_cast<double>(d.count - 1);
    a.bound_sum_squares += n1 * sigma_px * sigma_px * *bound * *bound;
    a.bound_dof += n1;
    a.jitter_with_bound += n1 * d.variance;
  }
}

// Per position: jitter, bias, efficiency, the per-position means run
// comparison tests, and the points of Fig. 12 (every stride-th position).
void add_positions(const RunData& data, const std::vector<ClassCornerNoise>& corner_noise,
                   const ReportOptions& options, SolverStudy& s, SolverAccumulator& acc) {
  const std::size_t stride =
      std::max<std::size_t>(1, (acc.groups.size() + options.max_points_per_series - 1) /
                                   std::max<std::size_t>(1, options.max_points_per_series));
  for (std::size_t i = 0; i < acc.groups.size(); ++i) {
    const PositionGroup& g = acc.groups[i];
    const store::PositionRecord& p = data.positions[g.position].record;
    const stats::Summary d = g.distance.summary();
    acc.position_abs.add(g.abs_error.summary().mean);
    acc.position_reprojection.add(g.reprojection.summary().mean);
    const stats::Summary gen = g.generalization.summary();
    if (gen.count > 0) acc.position_generalization.add(gen.mean);
    s.per_position.push_back({p.plan_index, g.abs_error.summary().mean,
                              g.reprojection.summary().mean, gen.count > 0 ? gen.mean : kNaN});
    acc.jitter.add(d);
    if (i % stride == 0) {
      s.plot_true_m.push_back(*p.true_distance_m);
      s.plot_estimated_m.push_back(d.mean);
    }
    if (!g.distance_class) continue;
    const std::size_t c = *g.distance_class;
    add_position_to_class(d, *p.true_distance_m, bound_of(p, s.scope), corner_noise[c].sigma_px,
                          acc.classes[c]);
  }
}

void finish_classes(const std::vector<ClassAccumulator>& acc,
                    std::vector<DistanceClassStudy>& classes) {
  for (std::size_t i = 0; i < classes.size(); ++i) {
    DistanceClassStudy& c = classes[i];
    const ClassAccumulator& a = acc[i];
    c.error_m = a.error.summary();
    c.reprojection_px = a.reprojection.summary();
    c.generalization_px = a.generalization.summary();
    c.error_x_m = a.error_x.summary();
    c.error_y_m = a.error_y.summary();
    c.error_z_m = a.error_z.summary();
    c.rotation_error_deg = a.rotation_error.summary();
    const stats::Summary bias = a.bias.summary();
    c.positions = bias.count;
    c.bias_m = bias.mean;
    c.bias_sd_m = bias.sd;
    c.jitter_m = a.jitter.sd();
    c.efficiency = a.bound_sum_squares > 0 ? a.jitter_with_bound / a.bound_sum_squares : kNaN;
  }
}

// Flips: the pose marker's rotation against the whole target's, per frame
// (counted on the pose marker's scope only).
void count_flips(const RunData& data, const PositionClasses& classes, const ReportOptions& options,
                 SolverStudy& s) {
  if (s.scope == "target") return;
  const auto it = data.flips.find(s.solver);
  if (it == data.flips.end()) return;
  for (const FlipSample& f : it->second) {
    const bool flip = f.angle_deg > options.flip_angle_deg;
    const auto [distance_class, angle_class] = classes.of(data.positions[f.position].record);
    count_flip(s, flip);
    if (distance_class) count_flip(s.classes[*distance_class], flip);
    if (angle_class) count_flip(s.by_viewing_angle[*angle_class], flip);
  }
}

SolverStudy study_solver(const RunData& data, const SolverScopeData& rows,
                         const std::vector<ClassCornerNoise>& corner_noise,
                         const ReportOptions& options) {
  const PositionClasses classes;
  SolverStudy s = empty_study(rows, classes);
  SolverAccumulator acc;
  add_estimates(data, rows, classes, options, s, acc);
  add_positions(data, corner_noise, options, s, acc);
  finish_classes(acc.classes, s.classes);
  count_flips(data, classes, options, s);
  s.reprojection_px = acc.reprojection.summary();
  s.generalization_px = acc.generalization.summary();
  s.error_m = acc.error.summary();
  s.abs_error_m = acc.abs_error.summary();
  s.relative_error_pct = acc.relative.summary();
  s.time_us = acc.time.summary();
  s.position_abs_error_m = acc.position_abs.summary();
  s.abs_error_p95_m = abs_error_p95(acc.x, acc.y);
  s.abs_error_ci95_m = mean_ci95(s.position_abs_error_m);
  s.position_reprojection_px = acc.position_reprojection.summary();
  s.position_generalization_px = acc.position_generalization.summary();
  fit_lines(acc.x, acc.y, acc.jitter.sd(), options, s);
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

// A marker that was visible (or, without visible markers recorded, detected)
// at a position: its side, the frames it was expected in, and its detections
// there (nullptr: none).
struct MarkerSizeItem {
  double side_px;
  std::size_t expected;
  const MarkerAtPosition* detected;
};

const MarkerAtPosition* detected_marker(const PositionData& p, int marker_id) {
  for (const MarkerAtPosition& m : p.markers)
    if (m.marker_id == marker_id) return &m;
  return nullptr;
}

// Visible markers with a non-finite side are left out and counted in
// nonfinite_sides.
std::vector<MarkerSizeItem> marker_size_items(const RunData& data, bool visible_recorded,
                                              std::size_t& nonfinite_sides) {
  std::vector<MarkerSizeItem> items;
  for (const PositionData& p : data.positions) {
    if (visible_recorded) {
      for (const store::VisibleMarker& v : p.record.visible_markers) {
        if (!std::isfinite(v.side_px)) {
          ++nonfinite_sides;
          continue;
        }
        items.push_back({v.side_px, p.frames, detected_marker(p, v.marker_id)});
      }
    } else {
      for (const MarkerAtPosition& m : p.markers) {
        if (std::isfinite(m.side_px)) items.push_back({m.side_px, 0, &m});
      }
    }
  }
  return items;
}

// Ten classes over the sides of the items, widened to whole pixels.
// Precondition: items is not empty.
stats::EqualWidthBins side_classes(const std::vector<MarkerSizeItem>& items) {
  double lo = items.front().side_px, hi = lo;
  for (const MarkerSizeItem& i : items) {
    lo = std::min(lo, i.side_px);
    hi = std::max(hi, i.side_px);
  }
  lo = std::floor(lo);
  hi = std::max(std::ceil(hi), lo + 1.0);
  return stats::EqualWidthBins(lo, hi, 10);
}

// Detection rate and corner quality against the marker's side length in px.
// Visible markers with a non-finite side are left out and counted in
// nonfinite_sides.
std::vector<MarkerSizeClass> study_marker_sizes(const RunData& data, bool visible_recorded,
                                                std::size_t& nonfinite_sides) {
  const std::vector<MarkerSizeItem> items =
      marker_size_items(data, visible_recorded, nonfinite_sides);
  if (items.empty()) return {};
  const stats::EqualWidthBins bins = side_classes(items);
  std::vector<MarkerSizeClass> out =
      empty_classes(bins, &MarkerSizeClass::lower_px, &MarkerSizeClass::upper_px);
  std::vector<stats::RunningSummary> edge(bins.count());
  std::vector<Pooled> jitter(bins.count());
  for (const MarkerSizeItem& i : items) {
    const auto c = bins.index_of(i.side_px);
    if (!c) continue;
    out[*c].expected += i.expected;
    if (i.detected == nullptr) continue;
    out[*c].detected += std::min(i.detected->frames_detected,
                                 visible_recorded ? i.expected : i.detected->frames_detected);
    if (i.detected->edge_fit_residual_px.count > 0)
      edge[*c].add(i.detected->edge_fit_residual_px.mean);
    jitter[*c].add_corners(*i.detected);
  }
  for (std::size_t i = 0; i < bins.count(); ++i) {
    out[i].edge_fit_residual_px = edge[i].summary();
    out[i].corner_jitter_px = jitter[i].sd();
  }
  return out;
}

std::vector<MissedMarker> study_missed_markers(const RunData& data) {
  std::vector<MissedMarker> out;
  for (const PositionData& p : data.positions) {
    if (p.frames == 0) continue;
    for (const store::VisibleMarker& v : p.record.visible_markers) {
      const MarkerAtPosition* m = detected_marker(p, v.marker_id);
      const std::size_t detected = m ? std::min(m->frames_detected, p.frames) : 0;
      if (detected >= p.frames) continue;
      out.push_back({p.record.plan_index, v.marker_id, v.side_px,
                     p.record.true_distance_m.value_or(kNaN), p.frames, detected});
    }
  }
  return out;
}

// The run's counts of positions and frames and what its positions recorded.
void count_positions(const RunData& data, RunStudy& study) {
  study.positions = data.positions.size();
  const stats::EqualWidthBins bins = distance_classes();
  study.class_example_positions.assign(bins.count(), {});
  for (const PositionData& p : data.positions) {
    study.failed_positions += p.record.status == store::PositionStatus::kFailed ? 1 : 0;
    study.frames += p.frames;
    study.visible_markers_recorded |= !p.record.visible_markers.empty();
    study.distance_bounds_recorded |= !p.record.distance_bounds.empty();
    study.viewing_angles_recorded |= p.record.true_viewing_angle_deg.has_value();
    study.true_poses_recorded |= p.record.true_pose.has_value();
    if (p.frames > 0 && p.record.true_distance_m) {
      const auto c = distance_class(bins, *p.record.true_distance_m);
      if (c && study.class_example_positions[*c].size() < 4)
        study.class_example_positions[*c].push_back(p.record.plan_index);
    }
    if (p.record.status == store::PositionStatus::kOk &&
        (!p.record.true_distance_m || !distance_class(bins, *p.record.true_distance_m))) {
      ++study.positions_outside_classes;
    }
  }
}

// Whether two studies of one scope measured the same poses: the same used
// estimates at the same positions, mean |error| within `tolerance` at each.
bool results_coincide(const SolverStudy& a, const SolverStudy& b, double tolerance) {
  if (a.scope != b.scope || a.used == 0 || a.used != b.used ||
      a.per_position.size() != b.per_position.size())
    return false;
  for (std::size_t i = 0; i < a.per_position.size(); ++i) {
    const PositionMeans& p = a.per_position[i];
    const PositionMeans& q = b.per_position[i];
    if (p.plan_index != q.plan_index || !(std::fabs(p.abs_error_m - q.abs_error_m) <= tolerance))
      return false;
  }
  return true;
}

void mark_coinciding(std::vector<SolverStudy>& solvers, double tolerance) {
  for (std::size_t i = 0; i < solvers.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (solvers[j].coincides_with.empty() &&
          results_coincide(solvers[j], solvers[i], tolerance)) {
        solvers[i].coincides_with = solvers[j].solver;
        break;
      }
    }
  }
}

// Per detector: the markers in view over the measured positions' frames, the
// stored counts, and the time per frame from the stage times.
std::vector<DetectorStudy> study_detectors(const RunData& data) {
  std::size_t in_view = 0, frames = 0;
  std::map<std::string, double> detect_s;  // by stage name
  for (const PositionData& p : data.positions) {
    if (p.record.status != store::PositionStatus::kOk) continue;
    in_view += p.record.visible_markers.size() * p.frames;
    frames += p.frames;
    for (const store::StageTime& t : p.record.stage_times)
      if (t.stage.rfind("detect", 0) == 0 && std::isfinite(t.seconds))
        detect_s[t.stage] += t.seconds;
  }
  std::vector<DetectorStudy> out;
  for (const DetectorData& d : data.detectors) {
    DetectorStudy s;
    s.detector = d.detector;
    s.primary = d.detector == data.run.description.primary_detector;
    s.views_in_view = in_view;
    s.views_found = d.views_found;
    s.corners_vs_truth = d.corners_vs_truth;
    s.misplaced = d.misplaced;
    s.corner_rms_px =
        d.corners_vs_truth > 0
            ? std::sqrt(d.corner_sum_squares_px2 / static_cast<double>(d.corners_vs_truth))
            : std::nan("");
    auto stage = detect_s.find("detect:" + d.detector);
    if (stage == detect_s.end() && s.primary) stage = detect_s.find("detect");
    s.time_per_frame_s = stage != detect_s.end() && frames > 0
                             ? stage->second / static_cast<double>(frames)
                             : std::nan("");
    out.push_back(s);
  }
  return out;
}

}  // namespace

std::string series_name(const std::string& solver, const std::string& detector,
                        const std::string& primary_detector) {
  return detector == primary_detector ? solver : solver + "@" + detector;
}

std::vector<std::string> RunStudy::coinciding(const SolverStudy& s) const {
  std::vector<std::string> out;
  for (const SolverStudy& other : solvers)
    if (other.scope == s.scope && other.coincides_with == s.solver) out.push_back(other.solver);
  return out;
}

RunStudy compute_study(const RunData& data, const ReportOptions& options) {
  RunStudy study;
  study.database = data.database;
  study.run = data.run;
  study.options = options;
  study.events = data.events;
  count_positions(data, study);
  study.corner_noise = corner_noise_by_class(data);
  // Each solver and scope on its own (study_solver reads `data` only): the
  // second half on a second thread, which halves this step on two cores.
  const std::size_t n = data.solvers.size(), half = n / 2;
  const auto study_range = [&](std::size_t from, std::size_t to) {
    std::vector<SolverStudy> out;
    for (std::size_t i = from; i < to; ++i)
      out.push_back(study_solver(data, data.solvers[i], study.corner_noise, options));
    return out;
  };
  auto second = std::async(std::launch::async, study_range, half, n);
  study.solvers = study_range(0, half);
  for (SolverStudy& s : second.get())
    study.solvers.push_back(std::move(s));
  for (const SolverScopeData& rows : data.solvers)
    study.estimates += rows.samples.size();
  mark_coinciding(study.solvers, options.coincidence_m);
  study.stages = study_stages(data);
  study.detectors = study_detectors(data);
  study.nonfinite_detections = data.nonfinite_detections;
  study.marker_sizes =
      study_marker_sizes(data, study.visible_markers_recorded, study.nonfinite_visible_markers);
  study.missed_markers = study_missed_markers(data);
  return study;
}

}  // namespace db::report
