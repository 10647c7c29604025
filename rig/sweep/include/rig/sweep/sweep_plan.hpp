// rig::sweep::SweepPlan: the ordered list of bench positions a sweep visits.
//
// Positions are carriage positions in bench coordinates, millimetres (the
// frame of motion::Bench::move_to and vision::RigGeometry). A plan is made in
// one of three ways:
//   grid    a rectangle of rows of constant Y, X the fast axis, serpentine or not;
//   CSV     a list of positions from a file (any order, any shape);
//   paper   the protocol of Maidi et al., "A performance study for camera pose
//           estimation using visual marker based tracking", Machine Vision and
//           Applications 21 (2010) §3.3: 1,939 bench positions whose
//           camera-target distances cover ten distance classes.
// A plan knows nothing of the bench: whether its positions lie inside a
// drive's soft limits is checked by load_sweep_config (rig/sweep/sweep_config.hpp)
// before the bench moves.
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace rig::sweep {

// A plan that cannot be made: a malformed grid, CSV file or stored JSON plan.
// The message names the input (the CSV file and line, "grid", "plan JSON"),
// the offending value and what was expected.
class PlanError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One commanded carriage position, bench frame, mm.
struct PlanPosition {
  double x_mm = 0, y_mm = 0;
};

class SweepPlan {
 public:
  // The largest plan accepted (a grid step typed in metres instead of
  // millimetres must fail at once, not fill the memory). At the simulated
  // bench's ~1 s per position this is still more than a week of sweeping.
  static constexpr std::size_t kMaxPositions = 1000000;

  // A rectangular grid, mm. X is the fast axis: rows of constant Y from y_min
  // to y_max, each row from x_min to x_max. Both ends are included; the last
  // step of an axis is shorter when the range is not a whole number of steps,
  // so x_max and y_max are visited exactly. min == max gives one value.
  // serpentine reverses every other row (row 0 runs x_min -> x_max, row 1
  // x_max -> x_min, ...), which halves the travel between rows.
  struct Grid {
    double x_min_mm = 0, x_max_mm = 0, x_step_mm = 1;
    double y_min_mm = 0, y_max_mm = 0, y_step_mm = 1;
    bool serpentine = true;
  };

  // An empty plan (size() == 0); every factory below returns at least one position.
  SweepPlan() = default;

  // Preconditions: every value finite, steps > 0, min <= max, at most
  // kMaxPositions positions. Throws PlanError
  // ("grid: x_step_mm = -5: expected a finite number > 0").
  static SweepPlan grid(const Grid& grid);

  // Reads positions from a CSV file: the first line that is neither blank nor
  // a comment is the header "x_mm,y_mm"; every following such line is one
  // position "X,Y" (finite numbers, mm). '#' starts a comment (a whole line or
  // the rest of a line); blank lines, spaces around values, CRLF line ends and
  // a UTF-8 byte order mark (spreadsheet exports) are accepted. Throws PlanError "PATH:LINE: ..."
  // naming the text found and what was expected, or "PATH: ..." for an unreadable file or a file
  // without positions.
  static SweepPlan from_csv(const std::string& path);

  // The paper's protocol over the box [x_min, x_max] x [y_min, y_max], mm:
  // 7 rows x 277 columns, evenly spaced with both ends included, serpentine
  // (7 * 277 = 1939 positions). On a rig whose camera looks along bench X at
  // the target (config/rigs/sim.toml), X sets the camera-target distance and
  // the 277 columns put about 28 positions in each of the ten distance
  // classes; the 7 rows add lateral offsets. Preconditions: finite values,
  // x_min < x_max, y_min < y_max; otherwise PlanError.
  static SweepPlan paper(double x_min_mm, double x_max_mm, double y_min_mm, double y_max_mm);
  static constexpr int kPaperRows = 7;
  static constexpr int kPaperColumns = 277;

  const std::vector<PlanPosition>& positions() const { return positions_; }
  std::size_t size() const { return positions_.size(); }
  // What the plan is, for logs and the run record, e.g.
  // "grid x 0..900 step 50 mm, y 100..200 step 50 mm, serpentine (57 positions)".
  const std::string& description() const { return description_; }

  // {"description": "...", "positions": [[x_mm, y_mm], ...]}, as stored with a
  // run. Doubles round-trip exactly.
  nlohmann::json to_json() const;
  // The inverse of to_json (for resuming a run). Throws PlanError "plan JSON:
  // ..." naming the malformed element (not an object, a missing or mistyped
  // key, an entry that is not a pair of finite numbers, no positions, more
  // than kMaxPositions).
  static SweepPlan from_json(const nlohmann::json& json);

 private:
  SweepPlan(std::vector<PlanPosition> positions, std::string description)
      : positions_(std::move(positions)), description_(std::move(description)) {}

  std::vector<PlanPosition> positions_;
  std::string description_;
};

}  // namespace rig::sweep
