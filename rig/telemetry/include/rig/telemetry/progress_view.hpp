// Progress of a sweep as seen through its telemetry messages: the progress bar
// of `rig sweep`, the plain log lines when there is no terminal, and the live
// view of `rig monitor`.
//
// Messages (published by the controller, one JSON object each):
//   run_start {run_id, database, plan_size, first_index, resumed, solvers[], frames_per_position,
//              sweep_file, plan (its description)}
//   position  {run_id, database, plan_index, completed, plan_size, status "ok"|"failed",
//              failure_reason,
//              commanded{x_mm,y_mm}, measured{x_mm,y_mm}, true_distance_m, markers_detected,
//              estimates[{solver, scope "0"(marker id)|"target", distance_m, distance_error_m,
//              reprojection_error_px, generalization_error_px|null, converged,
//              applicable (false: the solver does not apply to the scope)}],
//              stage_times_s{...}, elapsed_s}
//   fault     {run_id, plan_index, kind, message, action}
//   state     {run_id, state "running"|"paused"|"stopping"}
//   run_stop  {run_id, status "completed"|"aborted"|"failed", reason, positions_ok,
//              positions_failed, stored, plan_size, elapsed_s}
// Missing or mistyped fields are shown as "-", never thrown on: a monitor
// must survive a newer or older controller.
//
// Everything is computed from the messages (time from their "elapsed_s", not
// from a clock), so the same messages always give the same text.
#pragma once

#include <iosfwd>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace rig::telemetry {

// A duration for people: "0s", "59s", "1m23s", "2h05m"; "--" if negative or
// not finite. Seconds are rounded to the nearest whole second.
std::string format_duration(double seconds);

class ProgressView {
 public:
  // `smoothing`: weight (0, 1] of the newest seconds-per-position sample in
  // the exponentially weighted mean behind the ETA. Higher follows changes of
  // pace (e.g. a slower region of the plan) sooner but jitters more with
  // single slow positions (retries); 0.2 averages over roughly the last 5-10.
  explicit ProgressView(double smoothing = 0.2);

  // Takes in one telemetry message. A run_start clears the previous run.
  // A monitor that joins mid-run (no run_start seen) still gets progress and
  // ETA from the position messages, which carry completed and plan_size.
  void update(const nlohmann::json& message);

  // One line of at most `width` characters (if width >= 20):
  //   [#########-----------]  45.0%  90/201  ETA 1m23s  failed 2  running
  // The bar is left out when it would be narrower than 10 characters.
  std::string progress_line(int width) const;

  // One plain line for a position message, for logs and non-terminal output:
  //   position 12 (13/201) ok: x 100.000 y 50.000 mm, true 0.6100 m, 4 markers,
  //   best lm (target) -1.23 mm, 12.3 s
  std::string log_line(const nlohmann::json& position) const;

  // One plain line for any message (position: log_line).
  std::string describe(const nlohmann::json& message) const;

  // The latest estimate per solver and scope (marker, whole target): distance
  // error (mm, or µm where mm would round to 0.00), reprojection and
  // generalization errors (px), convergence (every column "n/a" for a solver
  // that does not apply to the scope); one row each, solvers in the run's order, columns
  // aligned to the longest solver name. At most `max_rows` rows (besides the
  // title and the heading): the rest are summarised in one line (how many,
  // how many converged, the largest |distance error| among them).
  std::string solver_table(int max_rows = 1000) const;

  // The monitor's screen, at most `height` - 1 lines of at most `width`
  // characters, so that it never scrolls a terminal of that size: run id,
  // sweep file and database (the database from any position message for a
  // monitor that joined late), the progress line with the ETA, the solver
  // table cut to the rows that fit, last fault and the last message.
  std::string dashboard(int width, int height = 24) const;

  // "waiting" (no message yet), "running", "paused", then the run_stop status
  // ("completed", "aborted", "failed").
  const std::string& state() const { return state_; }
  bool stopped() const { return stopped_; }
  int completed() const { return completed_; }
  int plan_size() const { return plan_size_; }
  int failed() const { return failed_; }
  // Exponentially weighted mean of seconds per stored position, from the
  // differences of "elapsed_s" between position messages (divided by the
  // difference of "completed", so missed messages do not skew it). An interval
  // during which the run paused is left out. nullopt until one interval is known.
  std::optional<double> seconds_per_position() const { return seconds_per_position_; }
  // seconds_per_position x positions left; 0 once the plan is done.
  std::optional<double> eta_s() const;

 private:
  struct SolverRow {
    std::string solver;
    std::string scope;
    nlohmann::json estimate;
  };

  double smoothing_;
  std::string state_ = "waiting";
  bool stopped_ = false;
  std::optional<long long> run_id_;
  std::string database_;
  nlohmann::json run_start_;
  std::vector<std::string> solver_order_;
  int completed_ = 0;
  int plan_size_ = 0;
  int failed_ = 0;
  std::optional<double> seconds_per_position_;
  // Reference for the next seconds-per-position sample.
  std::optional<double> reference_elapsed_s_;
  int reference_completed_ = 0;
  bool first_position_of_run_ = false;  // its interval covers one position
  bool paused_since_reference_ = false;
  std::vector<SolverRow> rows_;
  std::optional<long long> rows_plan_index_;
  std::string last_fault_;
  std::string last_message_;
};

// Shows a sweep's progress on a stream as messages come. On a terminal: one
// progress bar redrawn in place ("\r", erase to end of line), with run start,
// faults, pauses and run stop printed as lines above it. Otherwise: one
// describe() line per message. This is `rig sweep`'s progress output.
class ProgressPrinter {
 public:
  ProgressPrinter(std::ostream& out, bool terminal, int width);
  void update(const nlohmann::json& message);
  const ProgressView& view() const { return view_; }

 private:
  std::ostream& out_;
  bool terminal_;
  int width_;
  ProgressView view_;
};

// `rig ctl status` for people: the reply's status object as
//   state running, run 7: 45 of 201 positions stored (22.4 %), at plan index 45, ETA 1m23s
// with "-" for what the reply lacks.
std::string describe_status(const nlohmann::json& status);

// Whether a file descriptor (1 standard output, 2 standard error) is a
// terminal, and its width in columns (`fallback` if it is not a terminal or
// does not say).
bool is_terminal(int file_descriptor);
bool stdout_is_terminal();
int terminal_width(int fallback = 80, int file_descriptor = 1);
// Its height in rows (`fallback` likewise).
int terminal_height(int fallback = 24, int file_descriptor = 1);

}  // namespace rig::telemetry
