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

std::string clip(std::string line, int width) {
  if (width > 0 && static_cast<int>(line.size()) > width) line.resize(width);
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
    plan_size_ = static_cast<int>(number(message, "plan_size").value_or(0));
    if (message.contains("solvers") && message["solvers"].is_array())
      for (const auto& s : message["solvers"])
        if (s.is_string()) solver_order_.push_back(s.get<std::string>());
    state_ = "running";
    reference_elapsed_s_ = 0.0;  // elapsed_s counts from the run's start
    first_position_of_run_ = true;
  } else if (type == "position") {
    if (!stopped_) state_ = "running";
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

std::string ProgressView::solver_table() const {
  if (rows_.empty()) return "no solver estimates yet\n";
  std::vector<SolverRow> rows = rows_;
  auto rank = [&](const SolverRow& r) {
    const auto at = std::find(solver_order_.begin(), solver_order_.end(), r.solver);
    return std::make_tuple(at - solver_order_.begin(), r.scope == "target", r.scope);
  };
  std::stable_sort(rows.begin(), rows.end(),
                   [&](const SolverRow& a, const SolverRow& b) { return rank(a) < rank(b); });
  std::ostringstream out;
  char buf[256];
  std::snprintf(buf, sizeof buf, "%-12s %-10s %16s %14s %16s  %s\n", "solver", "scope",
                "distance error", "reprojection", "generalization", "converged");
  out << "latest estimates (position "
      << (rows_plan_index_ ? std::to_string(*rows_plan_index_) : std::string("-")) << ")\n"
      << buf;
  for (const auto& r : rows) {
    const auto err = number(r.estimate, "distance_error_m");
    std::snprintf(
        buf, sizeof buf, "%-12s %-10s %16s %14s %16s  %s\n", r.solver.c_str(),
        scope_label(r.scope).c_str(),
        (fixed(err ? std::optional<double>(1e3 * *err) : std::nullopt, "%+.2f") + " mm").c_str(),
        (fixed(number(r.estimate, "reprojection_error_px"), "%.3f") + " px").c_str(),
        (fixed(number(r.estimate, "generalization_error_px"), "%.3f") + " px").c_str(),
        r.estimate.value("converged", false) ? "yes" : "no");
    out << buf;
  }
  return out.str();
}

std::string ProgressView::dashboard(int width) const {
  std::ostringstream out;
  if (run_start_.is_object() && !run_start_.empty())
    out << clip("run " + text(run_start_, "run_id") + "  " + text(run_start_, "sweep_file") +
                    "  ->  " + text(run_start_, "database"),
                width)
        << "\n";
  else if (run_id_)
    out << "run " << *run_id_ << "\n";
  else
    out << (state_ == "waiting" ? "waiting for telemetry\n" : "run (joined after its start)\n");
  out << progress_line(width) << "\n\n" << solver_table() << "\n";
  out << clip("last fault: " + (last_fault_.empty() ? std::string("none") : last_fault_), width)
      << "\n";
  out << clip("last: " + (last_message_.empty() ? std::string("-") : last_message_), width) << "\n";
  return out.str();
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

int terminal_width(int fallback, int file_descriptor) {
  winsize size{};
  if (is_terminal(file_descriptor) && ::ioctl(file_descriptor, TIOCGWINSZ, &size) == 0 &&
      size.ws_col > 0)
    return size.ws_col;
  return fallback;
}

}  // namespace rig::telemetry
