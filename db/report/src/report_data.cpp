#include "report_data.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <future>
#include <set>
#include <string_view>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "db/report/report.hpp"
#include "db/store/sqlite.hpp"
#include "db/store/store.hpp"

namespace db::report {

// The estimates are read in row order from a range of row ids that holds
// every estimate of the run's frames (kEstimateIdsQuery over the run's frame
// ids), each row kept when its frame is one of the run's: a sequential pass
// over the table instead of a join that descends the table's B-tree once
// per row (about half of the report's time on 1,000,000 estimates). The
// range is read in two parts, one per core (load_run).
// A solver's series is named after the solver for the run's primary
// detector and "SOLVER@DETECTOR" for another detector's corners
// (series_name, report.hpp): every table, figure and comparison keys by both.
const char* const kEstimateIdsQuery =
    "SELECT min(id), max(id) FROM estimates WHERE frame_id BETWEEN ?1 AND ?2";
const char* const kEstimatesQuery =
    "SELECT e.frame_id, e.solver, e.scope, e.r00, e.r01, e.r02, e.r10, e.r11, "
    "e.r12, e.r20, e.r21, e.r22, e.distance_m, e.reprojection_error_px, "
    "e.generalization_error_px, e.converged, e.termination, e.time_us, e.ambiguity_ratio, "
    "e.tx_m, e.ty_m, e.tz_m, e.detector "
    "FROM estimates e WHERE e.id BETWEEN ?1 AND ?2 ORDER BY e.id";

const char* const kDetectionsQuery =
    "SELECT p.plan_index, f.frame_index, d.marker_id, d.a_x_px, d.a_y_px, d.b_x_px, d.b_y_px, "
    "d.c_x_px, d.c_y_px, d.d_x_px, d.d_y_px, d.edge_fit_residual_px "
    "FROM positions p JOIN frames f ON f.position_id = p.id "
    "JOIN detections d ON d.frame_id = f.id "
    "WHERE p.run_id = ?1 AND d.detector = (SELECT primary_detector FROM runs WHERE id = ?1) "
    "ORDER BY p.plan_index, f.frame_index";

// Per detector with detections in the run: the markers in view it found
// (each marker once a frame), the true-corner RMS of those detections within
// kMisplacedPx of the truth, and how many were farther (a marker's id decoded
// at another place). The detectors of the run's estimates come from their pass.
const char* const kDetectorQuery =
    "SELECT d.detector, count(DISTINCT CASE WHEN v.marker_id IS NOT NULL THEN "
    "d.frame_id * 65536 + d.marker_id END), "
    "sum(CASE WHEN v.marker_id IS NOT NULL AND d.true_corner_rms_px <= 10.0 THEN "
    "d.true_corner_rms_px * d.true_corner_rms_px END), "
    "count(CASE WHEN v.marker_id IS NOT NULL AND d.true_corner_rms_px <= 10.0 THEN 1 END), "
    "count(CASE WHEN v.marker_id IS NOT NULL AND d.true_corner_rms_px > 10.0 THEN 1 END) "
    "FROM positions p JOIN frames f ON f.position_id = p.id "
    "JOIN detections d ON d.frame_id = f.id "
    "LEFT JOIN visible_markers v ON v.position_id = p.id AND v.marker_id = d.marker_id "
    "WHERE p.run_id = ?1 GROUP BY d.detector";

// What two snapshots of one file must agree on for the run's rows to be the
// same in both (load_run): every write to a run's positions, frames,
// detections and estimates happens while it is running, and a run the
// report reads is not; resuming it clears ended_at and ending it again
// stamps a new one (milliseconds).
const char* const kRunVersionQuery =
    "SELECT status, status_reason, ended_at, "
    "(SELECT count(*) FROM positions WHERE run_id = ?1), "
    "(SELECT max(id) FROM positions WHERE run_id = ?1), "
    "(SELECT max(id) FROM estimates) FROM runs WHERE id = ?1";
constexpr int kRunVersionColumns = 6;

const char* const kFramesQuery =
    "SELECT p.plan_index, f.frame_index, f.id FROM positions p "
    "JOIN frames f ON f.position_id = p.id "
    "WHERE p.run_id = ?1 ORDER BY p.plan_index, f.frame_index";

namespace {

// Rotation angle of R_a^T R_b for row-major rotations, degrees, in [0, 180].
double rotation_angle_deg(const std::array<double, 9>& R_a, const std::array<double, 9>& R_b) {
  // trace(R_a^T R_b) = sum_ij R_a[i][j] R_b[i][j]; angle = acos((trace - 1) / 2).
  double trace = 0;
  for (int i = 0; i < 9; ++i)
    trace += R_a[i] * R_b[i];
  const double c = std::clamp(0.5 * (trace - 1.0), -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

bool is_skipped(const std::string& termination) {
  return termination == "skipped" || termination == "not_applicable";
}

// The run to report, chosen inside the read transaction: its id and status
// by direct queries (no run's stored files are read to choose one).
std::int64_t pick_run(store::sqlite::Connection& connection, const std::string& database,
                      std::optional<std::int64_t> run_id) {
  if (run_id) {
    store::sqlite::Statement status(connection, "SELECT status FROM runs WHERE id = ?1");
    status.bind(1, *run_id);
    if (status.step()) {
      if (status.get_text(0) == store::to_string(store::RunStatus::kRunning)) {
        throw ReportInputError(database + ": run " + std::to_string(*run_id) +
                               " is still running; expected a completed, aborted or failed run");
      }
      return *run_id;
    }
    std::string known;
    store::sqlite::Statement ids(connection, "SELECT id FROM runs ORDER BY id");
    while (ids.step())
      known += (known.empty() ? "" : ", ") + std::to_string(ids.get_int64(0));
    throw ReportInputError(database + ": no run " + std::to_string(*run_id) +
                           " (runs: " + (known.empty() ? "none" : known) + ")");
  }
  store::sqlite::Statement latest(connection,
                                  "SELECT id FROM runs WHERE status = ?1 ORDER BY id DESC LIMIT 1");
  latest.bind(1, store::to_string(store::RunStatus::kCompleted));
  if (latest.step()) return latest.get_int64(0);
  store::sqlite::Statement count(connection, "SELECT count(*) FROM runs");
  count.step();
  throw ReportInputError(database + ": no completed run (" + std::to_string(count.get_int64(0)) +
                         " run(s), none completed); finish a sweep first or name one with --run");
}

// The slot in RunData::positions of a plan index met by a pass; every pass
// reads the snapshot the slots came from, so a miss means the file is
// inconsistent (a row of frames without its position).
class Slots {
 public:
  Slots(const std::string& database, std::int64_t run_id) : database_(database), run_id_(run_id) {}
  void add(std::int64_t plan_index, std::uint32_t slot) { slot_of_.emplace(plan_index, slot); }
  std::uint32_t at(std::int64_t plan_index, const char* table) const {
    const auto it = slot_of_.find(plan_index);
    if (it == slot_of_.end()) {
      throw store::StoreError(database_ + ": run " + std::to_string(run_id_) + " has " + table +
                              " at plan index " + std::to_string(plan_index) +
                              " but no such position; expected every row to belong to a stored "
                              "position (is the file damaged?)");
    }
    return it->second;
  }

 private:
  std::string database_;
  std::int64_t run_id_;
  std::unordered_map<std::int64_t, std::uint32_t> slot_of_;
};

// Per position: the corners of each marker over its frames.
struct CornerSeries {
  std::vector<std::array<double, 8>> corners;
  stats::RunningSummary edge;
};

// Mean side length of the quadrilaterals A-B-C-D of a series, px.
double mean_side_px(const std::vector<std::array<double, 8>>& corners) {
  double side = 0;
  for (const auto& c : corners) {
    for (int k = 0; k < 4; ++k) {
      const int n = (k + 1) % 4;
      side += std::hypot(c[2 * n] - c[2 * k], c[2 * n + 1] - c[2 * k + 1]);
    }
  }
  return side / (4.0 * static_cast<double>(corners.size()));
}

// One marker's detections at one position: its frames, edge-fit residuals,
// side and the scatter of each of its 8 corner coordinates about their mean.
MarkerAtPosition marker_at_position(int marker_id, const CornerSeries& s) {
  MarkerAtPosition m;
  m.marker_id = marker_id;
  m.frames_detected = s.corners.size();
  m.edge_fit_residual_px = s.edge.summary();
  m.side_px = mean_side_px(s.corners);
  if (s.corners.size() < 2) return m;
  for (int k = 0; k < 8; ++k) {
    double mean = 0;
    for (const auto& c : s.corners)
      mean += c[k];
    mean /= static_cast<double>(s.corners.size());
    for (const auto& c : s.corners)
      m.corner_sum_squares += (c[k] - mean) * (c[k] - mean);
    m.corner_dof += s.corners.size() - 1;
  }
  return m;
}

void flush_markers(std::map<int, CornerSeries>& series, PositionData& position) {
  for (const auto& [id, s] : series)
    position.markers.push_back(marker_at_position(id, s));
  series.clear();
}

// Opens the file through the Store, read-only. Missing, not SQLite, another
// program's, newer or older schema: input the user must fix, not a failure
// of this program, so ReportInputError.
store::Store open_for_report(const std::string& database) {
  store::StoreOptions options;
  options.read_only = true;
  try {
    return store::Store(database, options);
  } catch (const store::StoreError& e) {
    throw ReportInputError(e.what());
  }
}

// The run's description through the Store, its mutable columns (status,
// reason, end) from the snapshot.
store::Run read_run(store::sqlite::Connection& connection, const store::Store& store,
                    const std::string& database, std::int64_t id) {
  store::sqlite::Statement state(connection,
                                 "SELECT status, status_reason, ended_at FROM runs WHERE id = ?1");
  state.bind(1, id);
  state.step();
  store::Run run = store.run(id);
  run.status = store::run_status_from_text(database, state.get_text(0));
  run.status_reason = state.get_text(1);
  run.ended_at = state.get_optional_text(2);
  return run;
}

// The snapshot's positions, by plan index, each given its slot: the Store's
// records (a superset, positions being append-only) filtered to the plan
// indices the snapshot holds.
std::vector<PositionData> read_positions(store::sqlite::Connection& connection,
                                         const store::Store& store, const std::string& database,
                                         std::int64_t id, Slots& slots) {
  std::vector<std::int64_t> snapshot_indices;
  store::sqlite::Statement indices(connection,
                                   "SELECT plan_index FROM positions WHERE run_id = ?1 "
                                   "ORDER BY plan_index");
  indices.bind(1, id);
  while (indices.step())
    snapshot_indices.push_back(indices.get_int64(0));
  std::vector<PositionData> positions;
  std::size_t next = 0;
  for (store::PositionRecord& p : store.positions(id)) {
    if (next == snapshot_indices.size() || p.plan_index != snapshot_indices[next]) continue;
    ++next;
    slots.add(p.plan_index, static_cast<std::uint32_t>(positions.size()));
    PositionData pd;
    pd.record = std::move(p);
    positions.push_back(std::move(pd));
  }
  if (next != snapshot_indices.size()) {
    throw store::StoreError(database + ": run " + std::to_string(id) + ": position at plan index " +
                            std::to_string(snapshot_indices[next]) +
                            " disappeared while the report read it; expected positions to be "
                            "append-only");
  }
  return positions;
}

std::vector<store::RunEvent> read_events(store::sqlite::Connection& connection, std::int64_t id) {
  std::vector<store::RunEvent> events;
  store::sqlite::Statement select(connection,
                                  "SELECT at, plan_index, kind, message FROM run_events "
                                  "WHERE run_id = ?1 ORDER BY id");
  select.bind(1, id);
  while (select.step()) {
    events.push_back(store::RunEvent{select.get_text(0), select.get_optional_int64(1),
                                     select.get_text(2), select.get_text(3)});
  }
  return events;
}

// The run's frames by row id: the slot of their position and their index
// there. Row ids are dense within a run, so a vector over [first, last].
class RunFrames {
 public:
  struct Frame {
    std::uint32_t slot = 0, frame_index = 0;
    bool of_run = false;
  };
  std::int64_t first = 0, last = -1;  // none when last < first

  // The row id that splits [first, last] after `share` of it (0 < share <=
  // 1): last + 1 for share 1.
  std::int64_t split(double share) const {
    if (last < first) return last + 1;
    const auto size = static_cast<double>(last - first + 1);
    return first + std::max<std::int64_t>(1, static_cast<std::int64_t>(share * size));
  }

  const Frame* find(std::int64_t frame_id) const {
    if (frame_id < first || frame_id > last) return nullptr;
    const Frame& f = frames_[static_cast<std::size_t>(frame_id - first)];
    return f.of_run ? &f : nullptr;
  }
  void add(std::int64_t frame_id, std::uint32_t slot, std::uint32_t frame_index) {
    ids_.push_back({frame_id, {slot, frame_index, true}});
  }
  // After the last add().
  void index() {
    if (ids_.empty()) return;
    first = last = ids_.front().first;
    for (const auto& [id, f] : ids_) {
      first = std::min(first, id);
      last = std::max(last, id);
    }
    frames_.assign(static_cast<std::size_t>(last - first + 1), Frame{});
    for (const auto& [id, f] : ids_)
      frames_[static_cast<std::size_t>(id - first)] = f;
    ids_.clear();
  }

 private:
  std::vector<std::pair<std::int64_t, Frame>> ids_;
  std::vector<Frame> frames_;
};

// Every frame of the run: counted per position and indexed by row id.
RunFrames read_frames(store::sqlite::Connection& connection, std::int64_t id, const Slots& slots,
                      std::vector<PositionData>& positions) {
  store::sqlite::Statement frames(connection, kFramesQuery);
  frames.bind(1, id);
  RunFrames run_frames;
  while (frames.step()) {
    const std::uint32_t slot = slots.at(frames.get_int64(0), "frames");
    ++positions[slot].frames;
    run_frames.add(frames.get_int64(2), slot, static_cast<std::uint32_t>(frames.get_int64(1)));
  }
  run_frames.index();
  return run_frames;
}

// The columns of kEstimatesQuery.
namespace estimate_column {
enum : int {
  kFrameId = 0,
  kSolver = 1,
  kScope = 2,
  kRotation = 3,  // r00 .. r22, row-major: columns 3 .. 11
  kDistance = 12,
  kReprojection = 13,
  kGeneralization = 14,
  kConverged = 15,
  kTermination = 16,
  kTime = 17,
  kAmbiguity = 18,
  kTranslation = 19,  // tx, ty, tz: columns 19 .. 21
  kDetector = 22,
};
}  // namespace estimate_column

// The columns of kDetectionsQuery.
namespace detection_column {
enum : int {
  kPlanIndex = 0,
  kMarkerId = 2,
  kCorners = 3,  // a_x, a_y, b_x, ..., d_y: columns 3 .. 10
  kEdgeFitResidual = 11,
};
}  // namespace detection_column

// One row's numbers; absent or non-finite optional figures are NaN (the
// status is set by status_of).
EstimateSample sample_of(const store::sqlite::Statement& row, std::uint32_t slot) {
  EstimateSample s;
  s.position = slot;
  s.distance_m = row.get_double(estimate_column::kDistance);
  s.reprojection_px = row.get_double(estimate_column::kReprojection);
  if (!row.is_null(estimate_column::kGeneralization))
    s.generalization_px = row.get_double(estimate_column::kGeneralization);
  s.time_us = row.get_double(estimate_column::kTime);
  if (!row.is_null(estimate_column::kAmbiguity))
    s.ambiguity_ratio = row.get_double(estimate_column::kAmbiguity);
  if (!std::isfinite(s.generalization_px)) s.generalization_px = kNaN;
  if (!std::isfinite(s.time_us)) s.time_us = kNaN;
  if (!std::isfinite(s.ambiguity_ratio)) s.ambiguity_ratio = kNaN;
  return s;
}

// A converged estimate against its position's true pose (EstimateSample).
void add_pose_errors(const store::sqlite::Statement& row, const store::TruePose& truth,
                     EstimateSample& s) {
  std::array<double, 9> R{};
  for (int k = 0; k < 9; ++k)
    R[k] = row.get_double(estimate_column::kRotation + k);
  s.error_x_m = row.get_double(estimate_column::kTranslation) - truth.t_cam_target_m[0];
  s.error_y_m = row.get_double(estimate_column::kTranslation + 1) - truth.t_cam_target_m[1];
  s.error_z_m = row.get_double(estimate_column::kTranslation + 2) - truth.t_cam_target_m[2];
  s.rotation_error_deg = rotation_angle_deg(R, truth.R_cam_target);
}

// Converged, skipped (solver not applicable) or failed; a failure is counted
// under its termination. A converged estimate must have a finite distance
// and reprojection error; one that does not is a solver bug, counted as a
// failure under its own name rather than poisoning every mean of the report.
SampleStatus status_of(const store::sqlite::Statement& row, const EstimateSample& s,
                       std::map<std::string, std::size_t>& failures_by_termination) {
  if (row.get_int(estimate_column::kConverged) != 0) {
    if (std::isfinite(s.distance_m) && std::isfinite(s.reprojection_px)) {
      return SampleStatus::kConverged;
    }
    ++failures_by_termination["converged with a non-finite value"];
    return SampleStatus::kFailed;
  }
  const std::string termination = row.get_text(estimate_column::kTermination);
  if (is_skipped(termination)) return SampleStatus::kSkipped;
  ++failures_by_termination[termination];
  return SampleStatus::kFailed;
}

// One pass over a range of estimate rows: the solver x scope data in order
// of first appearance, the flip samples, and the converged rotations of the
// current frame by series, whose pairs become the flip samples. Rows come in
// row id order: a frame's rows together (a position is stored in one
// transaction), frames in the order they were stored. The passes over the
// frames below a frame id and over the frames from it add up (append) to the
// pass over both: each keeps a frame's rows together, and finish() puts every
// series in plan order either way.
class EstimatesPass {
 public:
  explicit EstimatesPass(const RunData& data) : data_(&data) {}

  // Reads the estimates of the run's frames whose frame row ids are in
  // [first_frame, last_frame]: the estimate rows of the row id range that
  // holds them all (kEstimateIdsQuery), keeping those of these frames.
  void read(store::sqlite::Connection& connection, const RunFrames& frames,
            std::int64_t first_frame, std::int64_t last_frame) {
    store::sqlite::Statement bounds(connection, kEstimateIdsQuery);
    bounds.bind(1, first_frame);
    bounds.bind(2, last_frame);
    if (!bounds.step() || bounds.is_null(0)) return;
    store::sqlite::Statement select(connection, kEstimatesQuery);
    select.bind(1, bounds.get_int64(0));
    select.bind(2, bounds.get_int64(1));
    while (select.step()) {
      const std::int64_t frame_id = select.get_int64(estimate_column::kFrameId);
      if (frame_id < first_frame || frame_id > last_frame) continue;  // the other part's
      const RunFrames::Frame* frame = frames.find(frame_id);
      if (frame == nullptr) continue;  // another run's frame
      enter_frame(*frame);
      add_row(select, key_of(select.get_text_view(estimate_column::kSolver),
                             select.get_text_view(estimate_column::kDetector),
                             select.get_text_view(estimate_column::kScope)));
    }
    flush_frame();
  }

  // Adds the pass over the rows after this pass's (read and flushed).
  void append(EstimatesPass&& later) {
    if (later.first_frame_ == nullptr) return;
    if (frame_ != nullptr && stored_before(*later.first_frame_, *frame_)) in_plan_order_ = false;
    in_plan_order_ = in_plan_order_ && later.in_plan_order_;
    if (first_frame_ == nullptr) first_frame_ = later.first_frame_;
    frame_ = later.frame_;
    for (std::size_t k = 0; k < later.keys_.size(); ++k) {
      const Key& key = later.keys_[k];
      SolverScopeData& from = later.solvers_[k];
      SolverScopeData& to = solvers_[key_of(key.solver, key.detector, key.scope)];
      to.samples.insert(to.samples.end(), from.samples.begin(), from.samples.end());
      for (const auto& [termination, n] : from.failures_by_termination)
        to.failures_by_termination[termination] += n;
    }
    for (auto& [series, flips] : later.flips_) {
      std::vector<FlipSample>& to = flips_[series];
      to.insert(to.end(), flips.begin(), flips.end());
    }
  }

  // The detectors of the rows read.
  std::set<std::string> detectors() const {
    std::set<std::string> out;
    for (const Key& k : keys_)
      out.insert(k.detector);
    return out;
  }

  // After the last append: every sample and flip into `data` in plan index
  // then frame order, the solvers sorted by series, then scope.
  void finish(RunData& data) {
    if (!in_plan_order_) {
      for (SolverScopeData& d : solvers_)
        std::stable_sort(d.samples.begin(), d.samples.end(),
                         [](const EstimateSample& a, const EstimateSample& b) {
                           return std::make_pair(a.position, a.frame) <
                                  std::make_pair(b.position, b.frame);
                         });
      for (auto& [series, flips] : flips_)
        std::stable_sort(flips.begin(), flips.end(), [](const FlipSample& a, const FlipSample& b) {
          return a.position < b.position;
        });
    }
    std::vector<std::size_t> order(solvers_.size());
    for (std::size_t i = 0; i < order.size(); ++i)
      order[i] = i;
    std::sort(order.begin(), order.end(), [this](std::size_t a, std::size_t b) {
      return std::tie(solvers_[a].solver, solvers_[a].scope) <
             std::tie(solvers_[b].solver, solvers_[b].scope);
    });
    for (std::size_t i : order)
      data.solvers.push_back(std::move(solvers_[i]));
    data.flips = std::move(flips_);
  }

 private:
  struct FrameRotations {
    bool has[2] = {false, false};
    std::array<double, 9> R[2];
  };
  struct Key {
    std::string solver, detector, scope;
    std::size_t series_id;  // into rotations_
  };
  struct SeriesRotations {
    std::string series;
    FrameRotations rotations;
  };

  static bool stored_before(const RunFrames::Frame& a, const RunFrames::Frame& b) {
    return std::make_pair(a.slot, a.frame_index) < std::make_pair(b.slot, b.frame_index);
  }

  void enter_frame(const RunFrames::Frame& frame) {
    if (&frame == frame_) return;
    flush_frame();
    if (frame_ != nullptr && stored_before(frame, *frame_))
      in_plan_order_ = false;  // a position stored again later (a retake)
    if (first_frame_ == nullptr) first_frame_ = &frame;
    frame_ = &frame;
  }

  // The index of (solver, detector, scope) in solvers_ (views valid until the
  // next row). Every frame names them in the same order, so the key after
  // the last one is tried first.
  std::size_t key_of(std::string_view solver, std::string_view detector, std::string_view scope) {
    for (std::size_t k = 0; k < keys_.size(); ++k) {
      const std::size_t i = (next_key_ + k) % keys_.size();
      if (keys_[i].solver == solver && keys_[i].scope == scope && keys_[i].detector == detector) {
        next_key_ = i + 1;
        return i;
      }
    }
    const std::string series = series_name(std::string(solver), std::string(detector),
                                           data_->run.description.primary_detector);
    std::size_t series_id = 0;
    while (series_id < rotations_.size() && rotations_[series_id].series != series)
      ++series_id;
    if (series_id == rotations_.size()) rotations_.push_back({series, {}});
    keys_.push_back({std::string(solver), std::string(detector), std::string(scope), series_id});
    solvers_.push_back(SolverScopeData{series, std::string(scope), {}, {}});
    next_key_ = keys_.size();
    return keys_.size() - 1;
  }

  void add_row(const store::sqlite::Statement& row, std::size_t key) {
    SolverScopeData& target = solvers_[key];
    EstimateSample s = sample_of(row, frame_->slot);
    s.frame = frame_->frame_index;
    s.status = status_of(row, s, target.failures_by_termination);
    if (s.status == SampleStatus::kConverged) {
      keep_rotation(row, key);
      const auto& truth = data_->positions[s.position].record.true_pose;
      if (truth) add_pose_errors(row, *truth, s);
    }
    target.samples.push_back(s);
  }

  // A converged estimate's rotation: [0] the pose marker's scope (a marker
  // id, "0" by default), [1] "target".
  void keep_rotation(const store::sqlite::Statement& row, std::size_t key) {
    const int which = keys_[key].scope == "target" ? 1 : 0;
    FrameRotations& fr = rotations_[keys_[key].series_id].rotations;
    fr.has[which] = true;
    for (int k = 0; k < 9; ++k)
      fr.R[which][k] = row.get_double(estimate_column::kRotation + k);
  }

  void flush_frame() {
    for (auto& [series, fr] : rotations_) {
      if (fr.has[0] && fr.has[1])
        flips_[series].push_back({frame_->slot, rotation_angle_deg(fr.R[0], fr.R[1])});
      fr.has[0] = fr.has[1] = false;
    }
  }

  const RunData* data_;                                   // the run and its positions' truth
  std::vector<Key> keys_;                                 // by index into solvers_
  std::vector<SolverScopeData> solvers_;                  // in order of first appearance
  std::vector<SeriesRotations> rotations_;                // one per series
  std::map<std::string, std::vector<FlipSample>> flips_;  // by series
  std::size_t next_key_ = 0;
  const RunFrames::Frame* first_frame_ = nullptr;
  const RunFrames::Frame* frame_ = nullptr;  // the current, then the last, frame
  bool in_plan_order_ = true;
};

// The run's state in a connection's snapshot (kRunVersionQuery), each
// column as text.
using RunVersion = std::vector<std::optional<std::string>>;
RunVersion run_version(store::sqlite::Connection& connection, std::int64_t run_id) {
  store::sqlite::Statement select(connection, kRunVersionQuery);
  select.bind(1, run_id);
  RunVersion version;
  if (select.step()) {
    for (int c = 0; c < kRunVersionColumns; ++c)
      version.push_back(select.get_optional_text(c));
  }
  return version;
}

// Reads the estimates of the run's frames [first_frame, last_frame] on a
// connection of its own, in a snapshot that agrees with `version`. False,
// with nothing read, when the run changed in between: the caller then reads
// them in its own snapshot.
bool read_in_own_snapshot(const std::string& database, std::int64_t run_id,
                          const RunVersion& version, const RunFrames& frames,
                          std::int64_t first_frame, std::int64_t last_frame, EstimatesPass& pass) {
  store::sqlite::Connection connection(database, SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX);
  connection.exec("PRAGMA query_only = ON");
  store::sqlite::Transaction transaction(connection, store::sqlite::Transaction::Kind::kRead);
  if (run_version(connection, run_id) != version) return false;
  pass.read(connection, frames, first_frame, last_frame);
  transaction.commit();
  return true;
}

// Detections with a non-finite corner or edge-fit residual are counted in
// data.nonfinite_detections and left out.
void read_detections(store::sqlite::Connection& connection, std::int64_t id, const Slots& slots,
                     RunData& data) {
  store::sqlite::Statement select(connection, kDetectionsQuery);
  select.bind(1, id);
  std::map<int, CornerSeries> series;
  std::int64_t current_plan = -1;
  while (select.step()) {
    const std::int64_t plan = select.get_int64(detection_column::kPlanIndex);
    if (plan != current_plan) {
      if (current_plan >= 0)
        flush_markers(series, data.positions[slots.at(current_plan, "detections")]);
      current_plan = plan;
    }
    std::array<double, 8> c;
    bool finite = true;
    for (int k = 0; k < 8; ++k) {
      c[k] = select.get_double(detection_column::kCorners + k);
      finite = finite && std::isfinite(c[k]);
    }
    const double edge = select.get_double(detection_column::kEdgeFitResidual);
    if (!finite || !std::isfinite(edge)) {
      ++data.nonfinite_detections;
      continue;
    }
    CornerSeries& s = series[select.get_int(detection_column::kMarkerId)];
    s.corners.push_back(c);
    s.edge.add(edge);
  }
  if (current_plan >= 0)
    flush_markers(series, data.positions[slots.at(current_plan, "detections")]);
}

// What kDetectorQuery counts, by detector.
std::map<std::string, DetectorData> count_detections(store::sqlite::Connection& connection,
                                                     std::int64_t id) {
  std::map<std::string, DetectorData> by_name;
  store::sqlite::Statement select(connection, kDetectorQuery);
  select.bind(1, id);
  while (select.step()) {
    DetectorData& d = by_name[select.get_text(0)];
    d.detector = select.get_text(0);
    d.views_found = static_cast<std::size_t>(select.get_int64(1));
    d.corner_sum_squares_px2 = select.get_optional_double(2).value_or(0);
    d.corners_vs_truth = static_cast<std::size_t>(select.get_int64(3));
    d.misplaced = static_cast<std::size_t>(select.get_int64(4));
  }
  return by_name;
}

// The run's detectors, the primary first, then by name: those of its
// detections (by_name) and of its estimates.
void list_detectors(std::map<std::string, DetectorData> by_name,
                    const std::set<std::string>& of_estimates, RunData& data) {
  for (const std::string& name : of_estimates)
    by_name[name].detector = name;
  const std::string& primary = data.run.description.primary_detector;
  if (by_name.count(primary) != 0) data.detectors.push_back(by_name[primary]);
  for (const auto& [name, d] : by_name)
    if (name != primary) data.detectors.push_back(d);
}

}  // namespace

RunData load_run(const std::string& database, std::optional<std::int64_t> run_id,
                 const std::function<void(RunData&)>& amend_truth, int estimate_readers) {
  RunData data;
  data.database = database;
  std::optional<store::Store> store(open_for_report(database));
  // One snapshot: every read of the run's rows is made in one read
  // transaction of this connection, so a sweep resumed or appending while
  // the report reads cannot make the passes disagree. The run's description
  // and its position records are read through the Store (its own
  // connection) after the snapshot began: positions are append-only and
  // immutable once written, so the Store sees a superset of the snapshot's
  // positions and keeping those of the snapshot gives exactly the snapshot's
  // records; the run's mutable columns (status, reason, end) are taken from
  // the snapshot.
  // NOMUTEX: this thread alone uses the connection, so SQLite need not lock
  // it around each of the 20 million column reads of a large run.
  store::sqlite::Connection connection(database, SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX);
  connection.exec("PRAGMA query_only = ON");
  store::sqlite::Transaction transaction(connection, store::sqlite::Transaction::Kind::kRead);
  const std::int64_t id = pick_run(connection, database, run_id);
  data.run = read_run(connection, *store, database, id);
  Slots slots(database, id);
  data.positions = read_positions(connection, *store, database, id, slots);
  store.reset();
  if (amend_truth) amend_truth(data);
  data.events = read_events(connection, id);
  const RunFrames frames = read_frames(connection, id, slots, data.positions);
  // The estimates in two parts by frame, on two cores: the later frames on
  // a second connection (read_in_own_snapshot, which gives them back when
  // its snapshot does not hold the same run) while this thread reads the
  // earlier frames, the detections and the detectors. The earlier part is
  // the smaller because the detections follow it; kFirstShare balances the
  // two threads on 1,000,000 estimates (bench_report).
  constexpr double kFirstShare = 0.36;
  const std::int64_t split = frames.split(estimate_readers > 1 ? kFirstShare : 1.0);
  EstimatesPass earlier(data), later(data);
  std::future<bool> later_read;
  if (split <= frames.last) {
    later_read = std::async(std::launch::async, read_in_own_snapshot, std::cref(database), id,
                            run_version(connection, id), std::cref(frames), split, frames.last,
                            std::ref(later));
  }
  earlier.read(connection, frames, frames.first, split - 1);
  read_detections(connection, id, slots, data);
  std::map<std::string, DetectorData> detectors = count_detections(connection, id);
  if (later_read.valid() && !later_read.get()) later.read(connection, frames, split, frames.last);
  earlier.append(std::move(later));
  earlier.finish(data);
  list_detectors(std::move(detectors), earlier.detectors(), data);
  transaction.commit();
  return data;
}

}  // namespace db::report
