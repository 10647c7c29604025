#include "report_document.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "svg_detail.hpp"

namespace db::report {

void Section::paragraph(std::string text) {
  Block b;
  b.kind = Block::Kind::kParagraph;
  b.text = std::move(text);
  blocks.push_back(std::move(b));
}

void Section::table(html::Table table) {
  Block b;
  b.kind = Block::Kind::kTable;
  b.table = std::move(table);
  blocks.push_back(std::move(b));
}

void Section::facts(std::vector<std::pair<std::string, std::string>> facts) {
  Block b;
  b.kind = Block::Kind::kFacts;
  b.facts = std::move(facts);
  blocks.push_back(std::move(b));
}

bool Section::figure(svg::Figure figure) {
  bool any = false;
  for (const svg::Series& s : figure.series) {
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      const bool positive_enough = !figure.y.log || s.y[i] > 0;
      any |= std::isfinite(s.x[i]) && std::isfinite(s.y[i]) && positive_enough;
    }
  }
  if (!any) return false;
  Block b;
  b.kind = Block::Kind::kFigure;
  b.figure = std::move(figure);
  blocks.push_back(std::move(b));
  return true;
}

std::string num(double value, int digits) {
  if (std::isnan(value)) return "n/a";
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.*g", digits, value);
  return buffer;
}

std::string colour_of(std::size_t index) {
  // The figures' own palette (Okabe-Ito), so that a solver drawn with an
  // explicit colour looks like a series coloured by the SVG library.
  return svg::detail::kPalette[index % static_cast<std::size_t>(svg::detail::kPaletteSize)];
}

int marker_of(std::size_t index) {
  return static_cast<int>(index % 10);
}

std::string series_label(const RunStudy& study, const SolverStudy& s) {
  std::string label = s.solver;
  for (const std::string& other : study.coinciding(s))
    label += " = " + other;
  return label;
}

namespace {

std::string run_line(const RunStudy& s) {
  return "store::Run " + std::to_string(s.run.id) + " of " + s.database + ": " +
         to_string(s.run.status) +
         (s.run.status_reason.empty() ? "" : " (" + s.run.status_reason + ")") + ", started " +
         s.run.started_at + ", ended " + s.run.ended_at.value_or("-") + ", rig " +
         s.run.description.software_version + " on " + s.run.description.host + ".";
}

Section overview(const ReportInput& in) {
  const RunStudy& s = in.study;
  Section sec{"overview", "What the run holds", {}};
  sec.paragraph(run_line(s));
  if (s.run.status != store::RunStatus::kCompleted) {
    sec.paragraph("This run did not complete: its figures cover only the positions it measured.");
  }
  html::Table t{"run", "What the run holds", {"quantity", "value"}, {}};
  auto row = [&](const std::string& k, const std::string& v) {
    t.rows.push_back({{k, "", ""}, {v, "num", ""}});
  };
  row("plan positions", std::to_string(s.run.description.plan_size));
  row("positions measured", std::to_string(s.positions));
  row("positions failed (no frames)", std::to_string(s.failed_positions));
  row("positions outside the distance classes", std::to_string(s.positions_outside_classes));
  row("frames", std::to_string(s.frames));
  row("estimates", std::to_string(s.estimates));
  row("solver x scope combinations", std::to_string(s.solvers.size()));
  row("viewing angles", s.viewing_angles_recorded ? "recorded" : "not recorded");
  row("true poses (per-axis and rotation errors)",
      s.true_poses_recorded ? "recorded" : "not recorded (runs before schema 4)");
  row("Cramér-Rao distance bounds", s.distance_bounds_recorded ? "recorded" : "not recorded");
  row("visible markers", s.visible_markers_recorded ? "recorded" : "not recorded");
  row("detections with a non-finite corner or edge residual (not used)",
      std::to_string(s.nonfinite_detections));
  row("visible markers with a non-finite side (not used)",
      std::to_string(s.nonfinite_visible_markers));
  sec.table(std::move(t));
  if (in.baseline) {
    sec.paragraph("Baseline: " + run_line(*in.baseline) +
                  " Baseline values are drawn dashed in the figures and listed in the tables; "
                  "differences are flagged only where they exceed " +
                  num(s.options.significance_k, 3) + " standard errors.");
  }
  sec.paragraph(
      "Scopes: \"0\" is the pose from the pose marker alone (4 corners; the other markers give "
      "the generalization error, paper §3.2); \"target\" is the pose from every detected marker. "
      "Distance error = estimated - true distance. Skipped estimates (a solver not applicable to "
      "the scope) are counted but excluded from every accuracy figure, as are estimates that did "
      "not converge.");
  return sec;
}

}  // namespace

namespace {

// Pictures of frames with the detections drawn, when the caller drew them
// from saved frames; else how to get them.
Section frames_section(const ReportInput& in) {
  Section sec{"frames", "Frames", {}};
  if (in.pictures.empty()) {
    sec.paragraph(
        "No pictures of frames: the run saved none ([capture] save_frames in the sweep file, "
        "docs/sweep-file.md), or they are no longer where it saved them.");
    return sec;
  }
  sec.paragraph(
      "A few frames per distance class and each solver's worst frame (pose marker), scaled "
      "down, with the detected corners A-D and marker ids drawn where the detections stored "
      "in the database put them.");
  for (const FramePicture& p : in.pictures) {
    Block b;
    b.kind = Block::Kind::kPicture;
    b.picture = &p;
    sec.blocks.push_back(std::move(b));
  }
  return sec;
}

}  // namespace

Document build_document(const ReportInput& in) {
  Document doc;
  doc.title = "rig report: run " + std::to_string(in.study.run.id);
  doc.sections.push_back(summary_section(in));
  doc.sections.push_back(overview(in));
  if (in.baseline) {
    Section sec{"against-baseline", "Against the baseline", {}};
    add_comparison(in, sec);
    doc.sections.push_back(std::move(sec));
  }
  if (!in.study.detectors.empty()) {
    Section sec{"detectors", "Detectors x solvers", {}};
    add_detector_tables(in, sec);
    doc.sections.push_back(std::move(sec));
  }
  // Scopes in order: the pose marker's (its id, "0" by default), then "target".
  std::vector<std::string> scopes;
  for (const SolverStudy& s : in.study.solvers) {
    if (std::find(scopes.begin(), scopes.end(), s.scope) == scopes.end()) scopes.push_back(s.scope);
  }
  std::stable_partition(scopes.begin(), scopes.end(),
                        [](const std::string& s) { return s != "target"; });
  for (const std::string& scope : scopes) {
    Section sec{"paper-" + scope,
                scope != "target"
                    ? "The paper's study, pose marker (scope \"" + scope + "\")"
                    : std::string("The paper's study, whole target (scope \"target\")"),
                {}};
    add_paper_tables(in, scope, sec);
    add_paper_figures(in, scope, sec);
    doc.sections.push_back(std::move(sec));
  }
  Section beyond{"beyond", "Beyond the paper", {}};
  add_beyond_tables(in, beyond);
  add_beyond_figures(in, beyond);
  doc.sections.push_back(std::move(beyond));
  doc.sections.push_back(frames_section(in));
  return doc;
}

}  // namespace db::report
