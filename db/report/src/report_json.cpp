// report.json: the study's numbers (per solver and scope, per class), the
// comparison, and every figure's series and every table of the page, so that
// anything on the page can be re-plotted or checked by a program. NaN (an
// undefined figure) is written as null.
#include <nlohmann/json.hpp>

#include "report_document.hpp"

namespace db::report {
namespace {

using nlohmann::json;

json to_json(const stats::Summary& s) {
  return {{"count", s.count}, {"mean", s.mean}, {"variance", s.variance},
          {"sd", s.sd},       {"min", s.min},   {"max", s.max}};
}

// A summary of values in degrees, in radians (report.json keeps SI).
json radians_json(const stats::Summary& deg) {
  constexpr double k = M_PI / 180.0;
  return {{"count", deg.count}, {"mean", deg.mean * k}, {"variance", deg.variance * k * k},
          {"sd", deg.sd * k},   {"min", deg.min * k},   {"max", deg.max * k}};
}

json camera_json(const store::Run& run) {
  if (!run.camera) return nullptr;
  const store::RunCamera& c = *run.camera;
  return {{"source", c.source}, {"device_id", c.device_id}, {"vendor", c.vendor},
          {"model", c.model},   {"serial", c.serial},       {"device_version", c.device_version}};
}

json files_json(const store::RunDescription& d) {
  json files = json::object();
  auto file = [&](const char* role, const store::StoredFile& f) {
    files[role] = {{"path", f.path}, {"sha256", f.sha256}};
  };
  file("sweep_file", d.sweep_file);
  file("camera_calibration", d.camera_calibration);
  file("target_layout", d.target_layout);
  file("rig_geometry", d.rig_geometry);
  file("bench_profile", d.bench_profile);
  return files;
}

// Where the run's truth comes from: "stored" (the sweep's own rig geometry and
// calibration) or "recomputed" with the files it was recomputed from.
json truth_json(const RunStudy& st) {
  if (!st.truth) return {{"source", "stored"}, {"files", json::array()}};
  json files = json::array();
  for (const TruthFile& f : st.truth->files)
    files.push_back({{"role", f.role}, {"path", f.path}, {"sha256", f.sha256}});
  return {{"source", "recomputed"}, {"files", files}};
}

json to_json(const SolverStudy& s) {
  json j{{"solver", s.solver},
         {"scope", s.scope},
         {"estimates", s.estimates},
         {"skipped", s.skipped},
         {"failed", s.failed},
         {"used", s.used},
         {"failures_by_termination", s.failures_by_termination},
         {"reprojection_px", to_json(s.reprojection_px)},
         {"generalization_px", to_json(s.generalization_px)},
         {"error_m", to_json(s.error_m)},
         {"abs_error_m", to_json(s.abs_error_m)},
         {"relative_error_pct", to_json(s.relative_error_pct)},
         {"time_us", to_json(s.time_us)},
         {"position_abs_error_m", to_json(s.position_abs_error_m)},
         {"abs_error_p95_m", s.abs_error_p95_m},
         {"abs_error_ci95_m", s.abs_error_ci95_m},
         {"coincides_with", s.coincides_with},
         {"position_reprojection_px", to_json(s.position_reprojection_px)},
         {"position_generalization_px", to_json(s.position_generalization_px)},
         {"ambiguity_checked", s.ambiguity_checked},
         {"ambiguous", s.ambiguous},
         {"flip_checked", s.flip_checked},
         {"flips", s.flips}};
  if (s.ols) {
    j["ols"] = {{"slope", s.ols->slope},
                {"slope_se", s.ols->slope_se},
                {"intercept_m", s.ols->intercept},
                {"intercept_se_m", s.ols->intercept_se},
                {"n", s.ols->n},
                {"residual_sd_m", s.ols->residual_sd},
                {"residual_variance_m2", s.ols->residual_variance},
                {"residual_rms_m", s.ols->residual_rms},
                {"r_squared", s.ols->r_squared}};
  }
  if (s.deming) {
    j["deming"] = {{"slope", s.deming->slope},
                   {"slope_se", s.deming->slope_se},
                   {"intercept_m", s.deming->intercept},
                   {"intercept_se_m", s.deming->intercept_se},
                   {"delta", s.deming_delta}};
  }
  json classes = json::array();
  for (const DistanceClassStudy& c : s.classes) {
    classes.push_back({{"lower_m", c.lower_m},
                       {"upper_m", c.upper_m},
                       {"error_m", to_json(c.error_m)},
                       {"reprojection_px", to_json(c.reprojection_px)},
                       {"generalization_px", to_json(c.generalization_px)},
                       {"positions", c.positions},
                       {"jitter_m", c.jitter_m},
                       {"bias_m", c.bias_m},
                       {"bias_sd_m", c.bias_sd_m},
                       {"efficiency", c.efficiency},
                       {"efficiency_below_bound", efficiency_below_bound(c)},
                       {"pose_error",
                        {{"x_m", to_json(c.error_x_m)},
                         {"y_m", to_json(c.error_y_m)},
                         {"z_m", to_json(c.error_z_m)},
                         {"rotation_rad", radians_json(c.rotation_error_deg)}}},
                       {"ambiguity_checked", c.ambiguity_checked},
                       {"ambiguous", c.ambiguous},
                       {"flip_checked", c.flip_checked},
                       {"flips", c.flips}});
  }
  j["classes"] = classes;
  json angles = json::array();
  for (const AngleClassStudy& a : s.by_viewing_angle) {
    angles.push_back({{"lower_deg", a.lower_deg},
                      {"upper_deg", a.upper_deg},
                      {"ambiguity_checked", a.ambiguity_checked},
                      {"ambiguous", a.ambiguous},
                      {"flip_checked", a.flip_checked},
                      {"flips", a.flips}});
  }
  j["by_viewing_angle"] = angles;
  return j;
}

json to_json(const RunStudy& st) {
  json solvers = json::array();
  for (const SolverStudy& s : st.solvers)
    solvers.push_back(to_json(s));
  json corner = json::array();
  for (const ClassCornerNoise& c : st.corner_noise)
    corner.push_back(
        {{"lower_m", c.lower_m}, {"upper_m", c.upper_m}, {"sigma_px", c.sigma_px}, {"dof", c.dof}});
  json sizes = json::array();
  for (const MarkerSizeClass& m : st.marker_sizes)
    sizes.push_back({{"lower_px", m.lower_px},
                     {"upper_px", m.upper_px},
                     {"expected", m.expected},
                     {"detected", m.detected},
                     {"edge_fit_residual_px", to_json(m.edge_fit_residual_px)},
                     {"corner_jitter_px", m.corner_jitter_px}});
  json missed = json::array();
  for (const MissedMarker& m : st.missed_markers)
    missed.push_back({{"plan_index", m.plan_index},
                      {"marker_id", m.marker_id},
                      {"side_px", m.side_px},
                      {"true_distance_m", m.true_distance_m},
                      {"frames", m.frames},
                      {"frames_detected", m.frames_detected}});
  json stages = json::array();
  for (const StageStudy& s : st.stages)
    stages.push_back({{"stage", s.stage},
                      {"seconds", to_json(s.seconds)},
                      {"median_s", s.median_s},
                      {"p95_s", s.p95_s}});
  json detectors = json::array();
  for (const DetectorStudy& d : st.detectors)
    detectors.push_back({{"detector", d.detector},
                         {"primary", d.primary},
                         {"views_found", d.views_found},
                         {"views_in_view", d.views_in_view},
                         {"corner_rms_px", d.corner_rms_px},
                         {"corners_vs_truth", d.corners_vs_truth},
                         {"misplaced", d.misplaced},
                         {"time_per_frame_s", d.time_per_frame_s}});
  json events = json::array();
  for (const store::RunEvent& e : st.events)
    events.push_back({{"at", e.at},
                      {"plan_index", e.plan_index ? json(*e.plan_index) : json(nullptr)},
                      {"kind", e.kind},
                      {"message", e.message}});
  return {{"database", st.database},
          {"run",
           {{"id", st.run.id},
            {"status", to_string(st.run.status)},
            {"status_reason", st.run.status_reason},
            {"started_at", st.run.started_at},
            {"ended_at", st.run.ended_at ? json(*st.run.ended_at) : json(nullptr)},
            {"plan_size", st.run.description.plan_size},
            {"software_version", st.run.description.software_version},
            {"host", st.run.description.host},
            {"primary_detector", st.run.description.primary_detector},
            {"camera", camera_json(st.run)},
            {"files", files_json(st.run.description)}}},
          {"truth", truth_json(st)},
          {"positions", st.positions},
          {"failed_positions", st.failed_positions},
          {"positions_outside_classes", st.positions_outside_classes},
          {"frames", st.frames},
          {"estimates", st.estimates},
          {"viewing_angles_recorded", st.viewing_angles_recorded},
          {"true_poses_recorded", st.true_poses_recorded},
          {"distance_bounds_recorded", st.distance_bounds_recorded},
          {"visible_markers_recorded", st.visible_markers_recorded},
          {"nonfinite_detections", st.nonfinite_detections},
          {"nonfinite_visible_markers", st.nonfinite_visible_markers},
          {"solvers", solvers},
          {"corner_noise", corner},
          {"marker_sizes", sizes},
          {"missed_markers", missed},
          {"stages", stages},
          {"detectors", detectors},
          {"events", events}};
}

json to_json(const svg::Axis& a) {
  return {{"label", a.label}, {"unit", a.unit}, {"log", a.log}};
}

}  // namespace

std::string render_json(const Document& document, const ReportInput& in) {
  const ReportOptions& o = in.study.options;
  json root{{"format", "rig-report/1"},
            {"options",
             {{"ambiguity_ratio_threshold", o.ambiguity_ratio_threshold},
              {"flip_angle_deg", o.flip_angle_deg},
              {"true_distance_sd_m", o.true_distance_sd_m},
              {"significance_k", o.significance_k}}},
            {"study", to_json(in.study)}};
  if (in.baseline) root["baseline"] = to_json(*in.baseline);
  json comparison = json::array();
  for (const ComparedFigure& f : in.comparison) {
    comparison.push_back({{"solver", f.solver},
                          {"scope", f.scope},
                          {"figure", f.figure},
                          {"candidate", f.candidate},
                          {"baseline", f.baseline},
                          {"difference", f.difference.difference},
                          {"standard_error", f.difference.standard_error},
                          {"z", f.difference.z},
                          {"significant", f.difference.significant},
                          {"counted", f.counted},
                          {"regression_k", f.regression_k},
                          {"worse", f.worse},
                          {"better", f.better}});
  }
  root["comparison"] = comparison;
  root["regressed"] = regressed(in.comparison);
  json figures = json::array();
  json tables = json::array();
  for (const Section& section : document.sections) {
    for (const Block& b : section.blocks) {
      if (b.kind == Block::Kind::kFigure) {
        json series = json::array();
        for (const svg::Series& s : b.figure.series)
          series.push_back({{"label", s.label},
                            {"x", s.x},
                            {"y", s.y},
                            {"y_error", s.y_error},
                            {"dashed", s.dashed}});
        figures.push_back({{"id", b.figure.id},
                           {"section", section.id},
                           {"title", b.figure.title},
                           {"caption", b.figure.caption},
                           {"x", to_json(b.figure.x)},
                           {"y", to_json(b.figure.y)},
                           {"series", series}});
      } else if (b.kind == Block::Kind::kTable) {
        json rows = json::array();
        for (const auto& row : b.table.rows) {
          json r = json::array();
          for (const html::Cell& c : row)
            r.push_back(c.text);
          rows.push_back(r);
        }
        tables.push_back({{"id", b.table.id},
                          {"section", section.id},
                          {"caption", b.table.caption},
                          {"header", b.table.header},
                          {"rows", rows}});
      }
    }
  }
  json header = json::array();
  for (const auto& [term, value] : run_header(in.study))
    header.push_back({term, value});
  root["header"] = header;
  root["figures"] = figures;
  json pictures = json::array();
  for (const FramePicture& p : in.pictures)
    pictures.push_back({{"plan_index", p.frame.plan_index},
                        {"frame_index", p.frame.frame_index},
                        {"reason", p.frame.reason},
                        {"width_px", p.width},
                        {"height_px", p.height},
                        {"scale", p.scale},
                        {"drawn", p.drawn}});
  root["pictures"] = pictures;
  root["tables"] = tables;
  // A damaged database's text may hold bytes that are not UTF-8: written as
  // U+FFFD, the report is still valid JSON (nlohmann's default throws).
  return root.dump(1, ' ', false, json::error_handler_t::replace);
}

}  // namespace db::report
