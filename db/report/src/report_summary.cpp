// The top of the report: what was measured with what (the run header) and
// one row per solver and scope with the figures an engineer decides on.
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "report_data.hpp"
#include "report_document.hpp"
#include "report_units.hpp"

namespace db::report {
namespace {

// "path (sha256 0123456789ab)", or "not stored" for a role the run lacks.
std::string file_fact(const store::StoredFile& f) {
  if (f.path.empty() && f.content.empty()) return "not stored";
  return (f.path.empty() ? std::string("(no path)") : f.path) + " (sha256 " +
         f.sha256.substr(0, 12) + ")";
}

// The simulated rig's camera says model "rig-sim" and device version
// "realism <profile>" (docs/simulated-rig.md).
std::string rig_fact(const store::Run& run) {
  if (!run.camera) return "not recorded (camera not recorded)";
  const store::RunCamera& c = *run.camera;
  // Aravis's own fake GigE camera (arv-fake-gv-camera) is never a bench camera.
  if (c.vendor == "Aravis" && c.model == "Fake")
    return "simulated camera (Aravis fake GigE camera; realism not reported)";
  if (c.model != "rig-sim") return "bench";
  const std::string prefix = "realism ";
  const std::string profile = c.device_version.rfind(prefix, 0) == 0
                                  ? c.device_version.substr(prefix.size())
                                  : "not reported";
  return "simulated rig (realism: " + profile + ")";
}

std::string camera_fact(const store::Run& run) {
  if (!run.camera) return "camera not recorded";
  const store::RunCamera& c = *run.camera;
  std::string text;
  auto add = [&](const std::string& label, const std::string& value) {
    if (value.empty()) return;
    text += (text.empty() ? "" : ", ") + label + value;
  };
  add("vendor ", c.vendor);
  add("model ", c.model);
  add("serial ", c.serial);
  add("device version ", c.device_version);
  add("device id ", c.device_id);
  if (text.empty()) text = "the camera did not identify itself";
  return text + " (source " + c.source + ")";
}

// Whether the solver has a counted figure worse (or better) than the
// baseline, and which.
std::string verdict_of(const ReportInput& in, const SolverStudy& s, std::string* css) {
  std::string worse, better;
  for (const ComparedFigure& f : in.comparison) {
    if (f.solver != s.solver || f.scope != s.scope) continue;
    if (f.worse) worse += (worse.empty() ? "" : "; ") + f.figure;
    if (f.better) better += (better.empty() ? "" : "; ") + f.figure;
  }
  if (!worse.empty()) {
    *css = "worse";
    return "worse: " + worse;
  }
  if (!better.empty()) {
    *css = "better";
    return "better: " + better;
  }
  css->clear();
  return "no significant change";
}

struct SummaryRow {
  const SolverStudy* study;
  const SolverStudy* baseline;
  double ratio;  // mean |error| over the baseline's; NaN without one
  bool worse;
};

std::vector<SummaryRow> summary_rows(const ReportInput& in) {
  std::vector<SummaryRow> rows;
  for (const SolverStudy& s : in.study.solvers) {
    if (!s.coincides_with.empty()) continue;
    const SolverStudy* b = in.baseline ? in.baseline->find(s.solver, s.scope) : nullptr;
    const double ratio = b != nullptr ? s.abs_error_m.mean / b->abs_error_m.mean : kNaN;
    bool worse = false;
    for (const ComparedFigure& f : in.comparison)
      worse |= f.solver == s.solver && f.scope == s.scope && f.worse;
    rows.push_back({&s, b, ratio, worse});
  }
  // Against a baseline: regressed solvers first, then by ratio, largest
  // first; alone: by mean |error|, largest first. NaN last.
  auto key = [&](const SummaryRow& r) {
    const double v = in.baseline ? r.ratio : r.study->abs_error_m.mean;
    return std::isnan(v) ? -1.0 : v;
  };
  std::stable_sort(rows.begin(), rows.end(), [&](const SummaryRow& a, const SummaryRow& b) {
    if (a.study->scope != b.study->scope) return a.study->scope != "target";
    if (a.worse != b.worse) return a.worse;
    return key(a) > key(b);
  });
  return rows;
}

html::Table summary_table(const ReportInput& in) {
  html::Table t{"summary",
                "Per solver and scope: mean |distance error| with the half-width of its 95 % "
                "confidence interval (Student's t over the per-position means), its sd and 95th "
                "percentile over every used estimate, the failure rate of the applicable "
                "estimates and the mean time per solve; worst first",
                {"solver", "scope", "estimates used", "mean |error| (m)", "± 95 % CI (m)", "sd (m)",
                 "95th percentile (m)", "failure rate", "time per solve (µs)"},
                {}};
  if (in.baseline) {
    t.header.insert(t.header.end(), {"baseline mean |error| (m)", "ratio to baseline", "verdict"});
    t.caption +=
        "; the ratio is this run's mean |error| over the baseline's, the verdict that "
        "of the comparison below (family-wise threshold)";
  }
  for (const SummaryRow& r : summary_rows(in)) {
    const SolverStudy& s = *r.study;
    const std::size_t applicable = s.estimates - s.skipped;
    std::vector<html::Cell> row{
        {series_label(in.study, s), "", ""},
        {s.scope, "", ""},
        {std::to_string(s.used), "num", ""},
        quantity_cell(s.abs_error_m.mean, Quantity::kLength),
        quantity_cell(s.abs_error_ci95_m, Quantity::kLength),
        quantity_cell(s.abs_error_m.sd, Quantity::kLength),
        quantity_cell(s.abs_error_p95_m, Quantity::kLength),
        applicable == 0 ? html::Cell{"n/a (does not apply)", "", ""}
                        : quantity_cell(fraction(s.failed, applicable), Quantity::kFraction),
        quantity_cell(s.time_us.mean, Quantity::kMicroseconds)};
    if (in.baseline) {
      std::string css;
      const std::string verdict =
          r.baseline ? verdict_of(in, s, &css) : std::string("not in the baseline");
      row.push_back(
          quantity_cell(r.baseline ? r.baseline->abs_error_m.mean : kNaN, Quantity::kLength));
      row.push_back(quantity_cell(r.ratio, Quantity::kPlain));
      row.push_back({verdict, css, ""});
    }
    t.rows.push_back(std::move(row));
  }
  return t;
}

// Which geometry and calibration the true distances, angles and bounds come
// from: the run's stored files, or the files `rig report --geometry` named.
std::string truth_fact(const RunStudy& st) {
  if (!st.truth) return "from the read-backs with the run's own rig geometry and calibration";
  std::string text = "recomputed from the read-backs with ";
  bool first = true;
  for (const TruthFile& f : st.truth->files) {
    text +=
        (first ? "" : ", ") + f.role + " " + f.path + " (sha256 " + f.sha256.substr(0, 12) + ")";
    first = false;
  }
  return text;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> run_header(const RunStudy& st) {
  const store::Run& run = st.run;
  const store::RunDescription& d = run.description;
  return {
      {"Run", std::to_string(run.id) + " of " + st.database + ", " + to_string(run.status) +
                  (run.status_reason.empty() ? "" : " (" + run.status_reason + ")") + ", " +
                  run.started_at + " to " + run.ended_at.value_or("-") + ", rig " +
                  d.software_version + " on " + d.host},
      {"Measured on", rig_fact(run)},
      {"Camera", camera_fact(run)},
      {"Sweep file", file_fact(d.sweep_file)},
      {"Camera calibration", file_fact(d.camera_calibration)},
      {"Target layout", file_fact(d.target_layout)},
      {"Rig geometry", file_fact(d.rig_geometry)},
      {"Bench profile", file_fact(d.bench_profile)},
      {"Truth", truth_fact(st)},
      {"Positions", std::to_string(st.positions) + " measured of " + std::to_string(d.plan_size) +
                        " planned, " + std::to_string(st.frames) + " frames, " +
                        std::to_string(st.estimates) + " estimates"},
  };
}

Section summary_section(const ReportInput& in) {
  Section sec{"run-summary", "Summary", {}};
  sec.facts(run_header(in.study));
  std::string coinciding;
  for (const SolverStudy& s : in.study.solvers) {
    const std::vector<std::string> others = in.study.coinciding(s);
    if (others.empty()) continue;
    coinciding +=
        (coinciding.empty() ? "" : "; ") + series_label(in.study, s) + " (scope " + s.scope + ")";
  }
  if (!coinciding.empty()) {
    sec.paragraph("Coinciding solvers, listed and drawn once: " + coinciding +
                  ". Their per-position mean |distance error| agree within " +
                  length_text(in.study.options.coincidence_m) + " at every position.");
  }
  if (in.baseline) {
    std::size_t worse = 0;
    for (const SummaryRow& r : summary_rows(in))
      worse += r.worse ? 1 : 0;
    sec.paragraph(worse == 0 ? "Against the baseline: no solver significantly worse."
                             : "Against the baseline: " + std::to_string(worse) +
                                   " solver(s) and scope(s) significantly worse (first rows).");
  }
  sec.table(summary_table(in));
  return sec;
}

}  // namespace db::report
