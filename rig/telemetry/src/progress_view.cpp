// Progress bar, log lines and the monitor's view, computed from telemetry messages.
#include "rig/telemetry/progress_view.hpp"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <sstream>
#include <tuple>

namespace rig::telemetry {
namespace {

using nlohmann::json;

std::optional<double> number(const json& m, const char* key) {
  if (!m.is_object() || !m.contains(key) || !m[key].is_number()) return std::nullopt;
  const double v = m[key].get<double>();
  if (!std::isfinite(v)) return std::nullopt;
  return v;
}

std::string text(const json& m, const char* key, const std::string& missing = "-") {
  if (!m.is_object() || !m.contains(key)) return missing;
  if (m[key].is_string()) return m[key].get<std::string>();
  if (m[key].is_number_integer()) return std::to_string(m[key].get<long long>());
  return missing;
}

// printf-style formatting of one number, "-" when it is missing.
std::string fixed(std::optional<double> v, const char* format) {
  if (!v) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, format, *v);
  return buf;
}

std::string scope_label(const std::string& scope) {
  return scope == "target" ? "target" : "marker " + scope;
}

// `line` cut to `width` columns (UTF-8 code points, so "µ" is one column
// and is never cut in half).
std::string clip(std::string line, int width) {
  if (width <= 0) return line;
  int columns = 0;
  for (std::size_t i = 0; i < line.size(); ++i) {
    if ((static_cast<unsigned char>(line[i]) & 0xC0) == 0x80) continue;
    if (++columns > width) {
      line.resize(i);
      break;
    }
  }
  return line;
}

}  // namespace

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "--";
  const long long s = std::llround(seconds);
  char buf[32];
  if (s < 60) {
    std::snprintf(buf, sizeof buf, "%llds", s);
  } else if (s < 3600) {
    std::snprintf(buf, sizeof buf, "%lldm%02llds", s / 60, s % 60);
  } else {
    std::snprintf(buf, sizeof buf, "%lldh%02lldm", s / 3600, (s % 3600) / 60);
  }
  return buf;
}

ProgressView::ProgressView(double smoothing) : smoothing_(std::clamp(smoothing, 1e-3, 1.0)) {}

void ProgressView::update(const json& message) {
  if (!message.is_object()) return;
  const std::string type = text(message, "type", "");
  if (type == "run_start") {
    *this = ProgressView(smoothing_);
    run_start_ = message;
    if (message.contains("run_id") && message["run_id"].is_number_integer())
      run_id_ = message["run_id"].get<long long>();
    database_ = text(message, "database", "");
    plan_size_ = static_cast<int>(number(message, "plan_size").value_or(0));
    if (message.contains("solvers") && message["solvers"].is_array())
      for (const auto& s : message["solvers"])
        if (s.is_string()) solver_order_.push_back(s.get<std::string>());
    state_ = "running";
    reference_elapsed_s_ = 0.0;  // elapsed_s counts from the run's start
    first_position_of_run_ = true;
  } else if (type == "position") {
    if (!stopped_) state_ = "running";
    if (message.contains("run_id") && message["run_id"].is_number_integer())
      run_id_ = message["run_id"].get<long long>();
    if (const std::string db = text(message, "database", ""); !db.empty()) database_ = db;
    plan_size_ = static_cast<int>(number(message, "plan_size").value_or(plan_size_));
    const int completed = static_cast<int>(number(message, "completed").value_or(completed_ + 1));
    if (text(message, "status") == "failed") ++failed_;
    const auto elapsed = number(message, "elapsed_s");
    if (elapsed && reference_elapsed_s_ && !paused_since_reference_) {
      const int positions = first_position_of_run_ ? 1 : completed - reference_completed_;
      const double interval = *elapsed - *reference_elapsed_s_;
      if (positions > 0 && interval >= 0) {
        const double sample = interval / positions;
        seconds_per_position_ =
            seconds_per_position_
                ? *seconds_per_position_ + smoothing_ * (sample - *seconds_per_position_)
                : sample;
      }
    }
    if (elapsed) reference_elapsed_s_ = elapsed;
    reference_completed_ = completed;
    completed_ = completed;
    first_position_of_run_ = false;
    paused_since_reference_ = false;
    if (message.contains("estimates") && message["estimates"].is_array() &&
        !message["estimates"].empty()) {
      for (const auto& e : message["estimates"]) {
        const std::string solver = text(e, "solver");
        const std::string scope = text(e, "scope");
        auto row = std::find_if(rows_.begin(), rows_.end(), [&](const SolverRow& r) {
          return r.solver == solver && r.scope == scope;
        });
        if (row == rows_.end()) {
          rows_.push_back({solver, scope, e});
          if (std::find(solver_order_.begin(), solver_order_.end(), solver) == solver_order_.end())
            solver_order_.push_back(solver);
        } else {
          row->estimate = e;
        }
      }
      if (message.contains("plan_index") && message["plan_index"].is_number_integer())
        rows_plan_index_ = message["plan_index"].get<long long>();
    }
  } else if (type == "state") {
    const std::string s = text(message, "state");
    if (!stopped_ && (s == "running" || s == "paused")) state_ = s;
    if (s == "paused") paused_since_reference_ = true;
  } else if (type == "fault") {
    last_fault_ = describe(message);
    if (text(message, "action") == "pause") {
      if (!stopped_) state_ = "paused";
      paused_since_reference_ = true;
    }
  } else if (type == "run_stop") {
    stopped_ = true;
    state_ = text(message, "status", "stopped");
    plan_size_ = static_cast<int>(number(message, "plan_size").value_or(plan_size_));
    failed_ = static_cast<int>(number(message, "positions_failed").value_or(failed_));
  }
  last_message_ = describe(message);
}

std::optional<double> ProgressView::eta_s() const {
  if (plan_size_ > 0 && completed_ >= plan_size_) return 0.0;
  if (!seconds_per_position_ || plan_size_ <= 0) return std::nullopt;
  return *seconds_per_position_ * (plan_size_ - completed_);
}

std::string ProgressView::progress_line(int width) const {
  const double fraction =
      plan_size_ > 0 ? std::clamp(static_cast<double>(completed_) / plan_size_, 0.0, 1.0) : 0.0;
  const auto eta = eta_s();
  std::ostringstream suffix;
  suffix << fixed(100.0 * fraction, " %5.1f%%") << "  " << completed_ << "/"
         << (plan_size_ > 0 ? std::to_string(plan_size_) : "?") << "  ETA "
         << (eta ? format_duration(*eta) : "--") << "  failed " << failed_ << "  " << state_;
  const std::string tail = suffix.str();
  const int bar = width - static_cast<int>(tail.size()) - 2;
  if (bar < 10) return clip(tail.substr(1), width);
  const int filled = static_cast<int>(std::floor(fraction * bar));
  return "[" + std::string(filled, '#') + std::string(bar - filled, '-') + "]" + tail;
}

std::string ProgressView::log_line(const json& p) const {
  std::ostringstream line;
  line << "position " << text(p, "plan_index") << " (" << text(p, "completed") << "/"
       << text(p, "plan_size") << ") ";
  const json& xy = p.contains("measured") && p["measured"].is_object() ? p["measured"]
                   : p.contains("commanded")                           ? p["commanded"]
                                                                       : json();
  const std::string where =
      "x " + fixed(number(xy, "x_mm"), "%.3f") + " y " + fixed(number(xy, "y_mm"), "%.3f") + " mm";
  if (text(p, "status") == "failed") {
    line << "FAILED: " << text(p, "failure_reason", "no reason given") << "; " << where;
    return line.str();
  }
  line << text(p, "status") << ": " << where << ", true "
       << fixed(number(p, "true_distance_m"), "%.4f") << " m, " << text(p, "markers_detected")
       << " markers";
  // Best: the converged estimate with the smallest |distance error|.
  const json* best = nullptr;
  if (p.contains("estimates") && p["estimates"].is_array())
    for (const auto& e : p["estimates"]) {
      const auto err = number(e, "distance_error_m");
      if (!err || !e.value("converged", false)) continue;
      if (!best || std::abs(*err) < std::abs(*number(*best, "distance_error_m"))) best = &e;
    }
  if (best)
    line << ", best " << text(*best, "solver") << " (" << scope_label(text(*best, "scope")) << ") "
         << fixed(1e3 * *number(*best, "distance_error_m"), "%+.2f") << " mm";
  else
    line << ", no converged estimate";
  line << ", " << fixed(number(p, "elapsed_s"), "%.1f") << " s";
  return line.str();
}

std::string ProgressView::describe(const json& m) const {
  const std::string type = text(m, "type", "");
  std::ostringstream line;
  if (type == "position") return log_line(m);
  if (type == "run_start") {
    line << "run " << text(m, "run_id") << " started: " << text(m, "plan_size")
         << " positions from index " << text(m, "first_index") << ", solvers ";
    std::string solvers;
    if (m.contains("solvers") && m["solvers"].is_array())
      for (const auto& s : m["solvers"])
        solvers += (solvers.empty() ? "" : ", ") + (s.is_string() ? s.get<std::string>() : "-");
    line << (solvers.empty() ? "-" : solvers) << ", " << text(m, "frames_per_position")
         << " frames per position, database " << text(m, "database");
    if (m.value("resumed", false)) line << " (resumed)";
  } else if (type == "fault") {
    line << "fault at position " << text(m, "plan_index") << ": " << text(m, "kind") << ": "
         << text(m, "message") << " (action: " << text(m, "action") << ")";
  } else if (type == "state") {
    line << "run " << text(m, "run_id") << " " << text(m, "state");
  } else if (type == "run_stop") {
    line << "run " << text(m, "run_id") << " " << text(m, "status");
    const std::string reason = text(m, "reason", "");
    if (!reason.empty()) line << " (" << reason << ")";
    line << ": " << text(m, "positions_ok") << " ok, " << text(m, "positions_failed")
         << " failed of " << text(m, "plan_size") << " positions in "
         << format_duration(number(m, "elapsed_s").value_or(-1));
  } else {
    line << (type.empty() ? "message" : type) << ": " << m.dump();
  }
  return line.str();
}

namespace {

// A distance error for a person: mm with two decimals, or µm with one where
// the mm would round to 0.00; "-" when missing.
std::string distance_error_text(std::optional<double> metres) {
  if (!metres) return "-";
  char buf[32];
  if (std::fabs(*metres) < 0.005e-3)
    std::snprintf(buf, sizeof buf, "%+.1f µm", 1e6 * *metres);
  else
    std::snprintf(buf, sizeof buf, "%+.2f mm", 1e3 * *metres);
  return buf;
}

// Display width of UTF-8 text: its code points (µ is one column).
int columns(const std::string& t) {
  int n = 0;
  for (unsigned char c : t)
    n += (c & 0xC0) != 0x80;
  return n;
}

std::string pad_left(const std::string& t, int width) {
  return std::string(static_cast<std::size_t>(std::max(0, width - columns(t))), ' ') + t;
}
std::string pad_right(const std::string& t, int width) {
  return t + std::string(static_cast<std::size_t>(std::max(0, width - columns(t))), ' ');
}

bool applies(const json& estimate) {
  return !estimate.is_object() || !estimate.contains("applicable") ||
         !estimate["applicable"].is_boolean() || estimate["applicable"].get<bool>();
}

}  // namespace

std::string ProgressView::solver_table(int max_rows) const {
  if (rows_.empty()) return "no solver estimates yet\n";
  std::vector<SolverRow> rows = rows_;
  auto rank = [&](const SolverRow& r) {
    const auto at = std::find(solver_order_.begin(), solver_order_.end(), r.solver);
    return std::make_tuple(at - solver_order_.begin(), r.scope == "target", r.scope);
  };
  std::stable_sort(rows.begin(), rows.end(),
                   [&](const SolverRow& a, const SolverRow& b) { return rank(a) < rank(b); });
  int name_width = 6;
  for (const auto& r : rows)
    name_width = std::max(name_width, columns(r.solver));
  auto line = [&](const std::string& solver, const std::string& scope, const std::string& error,
                  const std::string& reprojection, const std::string& generalization,
                  const std::string& converged) {
    return pad_right(solver, name_width) + " " + pad_right(scope, 9) + " " + pad_left(error, 11) +
           " " + pad_left(reprojection, 9) + " " + pad_left(generalization, 10) + "  " + converged +
           "\n";
  };
  std::ostringstream out;
  out << "latest estimates (position "
      << (rows_plan_index_ ? std::to_string(*rows_plan_index_) : std::string("-")) << ")\n"
      << line("solver", "scope", "dist. err", "reproj.", "general.", "converged");
  const std::size_t shown = rows.size() <= static_cast<std::size_t>(std::max(0, max_rows))
                                ? rows.size()
                                : static_cast<std::size_t>(std::max(0, max_rows - 1));
  for (std::size_t i = 0; i < shown; ++i) {
    const SolverRow& r = rows[i];
    if (!applies(r.estimate)) {
      out << line(r.solver, scope_label(r.scope), "n/a", "n/a", "n/a", "n/a");
      continue;
    }
    out << line(r.solver, scope_label(r.scope),
                distance_error_text(number(r.estimate, "distance_error_m")),
                fixed(number(r.estimate, "reprojection_error_px"), "%.3f") + " px",
                fixed(number(r.estimate, "generalization_error_px"), "%.3f") + " px",
                r.estimate.value("converged", false) ? "yes" : "no");
  }
  if (shown < rows.size()) {
    int converged = 0;
    std::optional<double> worst;
    for (std::size_t i = shown; i < rows.size(); ++i) {
      converged += rows[i].estimate.value("converged", false) ? 1 : 0;
      if (const auto e = number(rows[i].estimate, "distance_error_m"))
        if (!worst || std::fabs(*e) > std::fabs(*worst)) worst = e;
    }
    out << "... " << rows.size() - shown << " more rows: " << converged << " converged, largest "
        << "|error| " << distance_error_text(worst) << "\n";
  }
  return out.str();
}

std::string ProgressView::dashboard(int width, int height) const {
  std::ostringstream out;
  std::string head;
  if (run_start_.is_object() && !run_start_.empty())
    head = "run " + text(run_start_, "run_id") + "  " + text(run_start_, "sweep_file") + "  ->  " +
           (database_.empty() ? std::string("-") : database_);
  else if (run_id_)
    head = "run " + std::to_string(*run_id_) + " (joined after its start)  ->  " +
           (database_.empty() ? std::string("database not yet known") : database_);
  else
    head = state_ == "waiting" ? "waiting for telemetry" : "run (joined after its start)";
  out << clip(head, width) << "\n" << progress_line(width) << "\n\n";
  // Title, heading, blank line, last fault, last message and the three
  // lines above: what is left of height - 1 goes to the table's rows.
  const int table_rows = std::max(1, height - 1 - 3 - 2 - 3);
  std::istringstream table(solver_table(table_rows));
  for (std::string row; std::getline(table, row);)
    out << clip(row, width) << "\n";
  out << "\n";
  out << clip("last fault: " + (last_fault_.empty() ? std::string("none") : last_fault_), width)
      << "\n";
  out << clip("last: " + (last_message_.empty() ? std::string("-") : last_message_), width) << "\n";
  return out.str();
}

std::string describe_status(const json& status) {
  if (!status.is_object()) return "no status in the reply";
  const auto completed = number(status, "completed");
  const auto plan = number(status, "plan_size");
  std::ostringstream line;
  line << "state " << text(status, "state") << ", run " << text(status, "run_id") << ": "
       << text(status, "completed") << " of " << text(status, "plan_size") << " positions stored";
  if (completed && plan && *plan > 0) line << fixed(100.0 * *completed / *plan, " (%.1f %%)");
  line << ", at plan index " << text(status, "current_index") << ", ETA "
       << format_duration(number(status, "eta_s").value_or(-1));
  return line.str();
}

ProgressPrinter::ProgressPrinter(std::ostream& out, bool terminal, int width)
    : out_(out), terminal_(terminal), width_(width) {}

void ProgressPrinter::update(const json& message) {
  view_.update(message);
  const std::string type = message.is_object() ? text(message, "type", "") : "";
  if (!terminal_) {
    out_ << view_.describe(message) << "\n" << std::flush;
    return;
  }
  // "\r\x1b[K": back to the start of the line and erase it (ANSI EL).
  out_ << "\r\x1b[K";
  if (type != "position") out_ << view_.describe(message) << "\n";
  if (type != "run_stop") out_ << view_.progress_line(width_);
  out_ << std::flush;
}

bool is_terminal(int file_descriptor) {
  return ::isatty(file_descriptor) == 1;
}

bool stdout_is_terminal() {
  return is_terminal(STDOUT_FILENO);
}

int terminal_height(int fallback, int file_descriptor) {
  winsize size{};
  if (is_terminal(file_descriptor) && ::ioctl(file_descriptor, TIOCGWINSZ, &size) == 0 &&
      size.ws_row > 0)
    return size.ws_row;
  return fallback;
}

int terminal_width(int fallback, int file_descriptor) {
  winsize size{};
  if (is_terminal(file_descriptor) && ::ioctl(file_descriptor, TIOCGWINSZ, &size) == 0 &&
      size.ws_col > 0)
    return size.ws_col;
  return fallback;
}

}  // namespace rig::telemetry
