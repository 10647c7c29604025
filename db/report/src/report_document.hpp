#pragma once
// The report as one document model (private to db_report): sections of
// paragraphs, tables and figures, built once from the study
// (report_tables.cpp, report_figures.cpp) and written three ways: HTML
// (report_html.cpp), JSON (report_json.cpp) and CSV (report_csv.cpp), so
// that the three outputs cannot disagree.
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "db/report/html_page.hpp"
#include "db/report/report.hpp"
#include "db/report/svg_plot.hpp"

namespace db::report {

struct Block {
  enum class Kind { kParagraph, kTable, kFigure, kFacts, kPicture } kind = Kind::kParagraph;
  std::string text;
  std::vector<std::pair<std::string, std::string>> facts;  // term, value
  html::Table table;
  svg::Figure figure;
  const FramePicture* picture = nullptr;  // kPicture: one of ReportInput::pictures
};

struct Section {
  std::string id, title;
  std::vector<Block> blocks;
  void paragraph(std::string text);
  void table(html::Table table);
  void facts(std::vector<std::pair<std::string, std::string>> facts);
  // Adds the figure only if some series has a finite point (an empty
  // figure says nothing); returns whether it did.
  bool figure(svg::Figure figure);
};

struct Document {
  std::string title;
  std::vector<Section> sections;
};

// The inputs of every part of the document.
struct ReportInput {
  const RunStudy& study;
  const std::optional<RunStudy>& baseline;
  const std::vector<ComparedFigure>& comparison;
  const std::vector<FramePicture>& pictures;
};

Document build_document(const ReportInput& input);

// Parts of build_document.
void add_paper_tables(const ReportInput& input, const std::string& scope, Section& section);
void add_paper_figures(const ReportInput& input, const std::string& scope, Section& section);
void add_beyond_tables(const ReportInput& input, Section& section);
void add_beyond_figures(const ReportInput& input, Section& section);
void add_comparison(const ReportInput& input, Section& section);
// The detectors of the run against each other: detection rate, corner RMS
// against the truth, time per frame, and each solver's mean |distance
// error| on each detector's corners (pose-marker scope).
void add_detector_tables(const ReportInput& input, Section& section);
// The run header (what was measured, with which camera, calibration,
// geometry and bench or simulated rig) and the summary table: one row per
// solver and scope, worst first against a baseline (report_summary.cpp).
Section summary_section(const ReportInput& input);
// The header's facts alone (term, value), for the page and report.json.
std::vector<std::pair<std::string, std::string>> run_header(const RunStudy& study);

// k of n as a fraction in [0, 1] (detection, failure, ambiguity and flip
// rates); NaN when n is 0.
inline double fraction(std::size_t k, std::size_t n) {
  return n > 0 ? static_cast<double>(k) / static_cast<double>(n)
               : std::numeric_limits<double>::quiet_NaN();
}

// Number as text for tables and CSV: 6 significant digits, "n/a" for NaN.
std::string num(double value, int digits = 6);
// Colour of a solver in every figure (by its position in the sorted list).
std::string colour_of(std::size_t index);
// Marker shape of a solver in every figure (svg::Series::marker), by the same index.
int marker_of(std::size_t index);
// A solver's name with those that coincide with it ("ippe = opencv_ippe").
std::string series_label(const RunStudy& study, const SolverStudy& s);

std::string render_html(const Document& document);
// report.json: the study's numbers, every figure's series and every table.
std::string render_json(const Document& document, const ReportInput& input);
// One CSV file (name, content) per table, named after the table id.
std::vector<std::pair<std::string, std::string>> render_csv(const Document& document);

}  // namespace db::report
