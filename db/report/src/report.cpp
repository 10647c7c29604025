// db::report::Report: study, comparison and the three outputs (see db/report/report.hpp).
#include "db/report/report.hpp"

#include <cctype>
#include <filesystem>
#include <fstream>

#include "db/stats/error.hpp"
#include "report_data.hpp"
#include "report_document.hpp"
#include "report_study.hpp"

namespace db::report {

const SolverStudy* RunStudy::find(const std::string& solver, const std::string& scope) const {
  for (const SolverStudy& s : solvers) {
    if (s.solver == solver && s.scope == scope) return &s;
  }
  return nullptr;
}

RunReference RunReference::parse(const std::string& text) {
  RunReference ref;
  ref.database = text;
  const std::size_t colon = text.rfind(':');
  if (colon != std::string::npos && colon + 1 < text.size() && colon + 19 > text.size()) {
    bool digits = true;
    for (std::size_t i = colon + 1; i < text.size(); ++i)
      digits &= std::isdigit(static_cast<unsigned char>(text[i])) != 0;
    if (digits) {
      ref.database = text.substr(0, colon);
      ref.run_id = std::stoll(text.substr(colon + 1));
    }
  }
  if (ref.database.empty()) {
    throw ReportInputError("baseline \"" + text + "\": no database path; expected DB or DB:RUN");
  }
  return ref;
}

namespace {

// The stored truth of every position replaced by the recomputed one; a
// position the recomputation has no entry for has no known truth.
void replace_truth(const RecomputedTruth& truth, RunData& data) {
  for (PositionData& p : data.positions) {
    store::PositionRecord& r = p.record;
    const auto it = truth.positions.find(r.plan_index);
    const PositionTruth none;
    const PositionTruth& t = it == truth.positions.end() ? none : it->second;
    r.true_distance_m = t.true_distance_m;
    r.true_viewing_angle_deg = t.true_viewing_angle_deg;
    r.distance_bounds = t.distance_bounds;
    r.visible_markers = t.visible_markers;
  }
}

}  // namespace

// A statistic that cannot be computed from a run's stored values (a value
// so large that its square overflows, one that is not finite) means the
// database holds values no rig measured: bad input naming the database.
RunStudy study_run(const std::string& database, const ReportOptions& options) {
  RunData data = report::load_run(database, options.run_id);
  std::optional<RecomputedTruth> truth;
  if (options.recompute_truth) {
    std::vector<store::PositionRecord> positions;
    positions.reserve(data.positions.size());
    for (const PositionData& p : data.positions)
      positions.push_back(p.record);
    truth = options.recompute_truth(data.run, positions);
    replace_truth(*truth, data);
  }
  try {
    RunStudy study = report::compute_study(data, options);
    if (truth) {
      truth->positions.clear();  // the study keeps only the files it came from
      study.truth = std::move(truth);
    }
    return study;
  } catch (const stats::StatsError& e) {
    throw ReportInputError(database + ": run " + std::to_string(data.run.id) +
                           ": cannot be reported: " + e.what() +
                           " (a stored value, e.g. a distance, is beyond any physical range); "
                           "expected a database written by rig sweep");
  }
}

Report::Report(const std::string& database, const ReportOptions& options,
               const std::optional<RunReference>& baseline)
    : study_(study_run(database, options)) {
  if (baseline) {
    ReportOptions baseline_options = options;
    baseline_options.run_id = baseline->run_id;
    // The baseline is judged against its own stored truth.
    baseline_options.recompute_truth = nullptr;
    baseline_ = study_run(baseline->database, baseline_options);
    comparison_ = compare_runs(study_, *baseline_, options.significance_k);
  }
}

bool Report::regressed() const {
  return db::report::regressed(comparison_);
}

namespace {

void write_file(const std::filesystem::path& path, const std::string& content) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << content;
  out.close();
  if (!out) throw std::runtime_error(path.string() + ": cannot write the report file");
}

}  // namespace

ReportFiles Report::write(const std::string& out_dir) const {
  const std::filesystem::path dir(out_dir);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    throw std::runtime_error(out_dir + ": cannot create the output directory" +
                             (ec ? " (" + ec.message() + ")" : std::string()));
  }
  const report::ReportInput input{study_, baseline_, comparison_};
  const report::Document document = report::build_document(input);
  ReportFiles files;
  files.html = (dir / "report.html").string();
  write_file(files.html, report::render_html(document));
  files.json = (dir / "report.json").string();
  write_file(files.json, report::render_json(document, input));
  for (const auto& [name, content] : report::render_csv(document)) {
    files.csv.push_back((dir / name).string());
    write_file(files.csv.back(), content);
  }
  return files;
}

}  // namespace db::report
