// db::store::Store: positions with their frames, detections and estimates; what a
// resume and a report read back.
#include <chrono>

#include "db/store/store.hpp"
#include "store_impl.hpp"

namespace db::store {

std::int64_t Store::Impl::write_rows(std::int64_t run_id, const PositionRecord& p,
                                     const std::string& where) {
  Impl& s = *this;
  try {
    s.insert_position.bind(1, run_id)
        .bind(2, p.plan_index)
        .bind(3, p.commanded_x_mm)
        .bind(4, p.commanded_y_mm)
        .bind(5, p.measured_x_mm)
        .bind(6, p.measured_y_mm)
        .bind(7, p.true_distance_m)
        .bind(8, p.settle_time_s)
        .bind(9, std::string_view(to_string(p.status)))
        .bind(10, p.failure_reason)
        .bind(11, p.true_viewing_angle_deg);
    for (int k = 0; k < 12; ++k) {
      std::optional<double> v;
      if (p.true_pose)
        v = k < 9 ? p.true_pose->R_cam_target[k] : p.true_pose->t_cam_target_m[k - 9];
      s.insert_position.bind(12 + k, v);
    }
    s.insert_position.run();
  } catch (const sqlite::ConstraintError& e) {
    if (e.extended_code == SQLITE_CONSTRAINT_UNIQUE) {
      throw DuplicatePosition(where + ": the run already has this position; nothing written");
    }
    throw;
  }
  const std::int64_t position_id = s.connection.last_insert_rowid();
  for (const DistanceBound& b : p.distance_bounds) {
    s.insert_bound.bind(1, position_id).bind(2, b.scope).bind(3, b.distance_sd_m_per_px).run();
  }
  for (const VisibleMarker& m : p.visible_markers) {
    s.insert_visible.bind(1, position_id).bind(2, m.marker_id).bind(3, m.side_px).run();
  }
  for (std::size_t i = 0; i < p.stage_times.size(); ++i) {
    s.insert_stage.bind(1, position_id)
        .bind(2, static_cast<std::int64_t>(i))
        .bind(3, p.stage_times[i].stage)
        .bind(4, p.stage_times[i].seconds)
        .run();
  }
  for (const FrameRecord& f : p.frames) {
    s.insert_frame.bind(1, position_id)
        .bind(2, f.index)
        .bind(3, f.camera_timestamp_ns)
        .bind(4, f.host_timestamp_ns)
        .bind(5, f.source)
        .bind(6, f.image_path)
        .bind(7, f.image_sha256)
        .run();
    const std::int64_t frame_id = s.connection.last_insert_rowid();
    for (const DetectionRecord& d : f.detections) {
      s.insert_detection.bind(1, frame_id).bind(2, d.marker_id).bind(3, d.rotation);
      for (int k = 0; k < 8; ++k)
        s.insert_detection.bind(4 + k, d.corners_px[k]);
      s.insert_detection.bind(12, d.contrast)
          .bind(13, d.bits_corrected)
          .bind(14, d.edge_fit_residual_px)
          .bind(15, d.detector)
          .bind(16, d.true_corner_rms_px)
          .run();
    }
    for (const EstimateRecord& e : f.estimates) {
      s.insert_estimate.bind(1, frame_id).bind(2, e.solver).bind(3, e.scope);
      for (int k = 0; k < 9; ++k)
        s.insert_estimate.bind(4 + k, e.R_cam_target[k]);
      for (int k = 0; k < 3; ++k)
        s.insert_estimate.bind(13 + k, e.t_cam_target_m[k]);
      s.insert_estimate.bind(16, e.distance_m)
          .bind(17, e.reprojection_error_px)
          .bind(18, e.generalization_error_px)
          .bind(19, e.iterations)
          .bind(20, e.converged ? 1 : 0)
          .bind(21, e.termination)
          .bind(22, e.time_us)
          .bind(23, e.ambiguity_ratio)
          .bind(24, e.detector)
          .run();
    }
  }
  return position_id;
}

void Store::append_position(std::int64_t run_id, const PositionRecord& p) {
  impl_->append(run_id, p, /*retake_failed=*/false);
}

void Store::retake_failed_position(std::int64_t run_id, const PositionRecord& p) {
  impl_->append(run_id, p, /*retake_failed=*/true);
}

void Store::Impl::append(std::int64_t run_id, const PositionRecord& p, bool retake_failed) {
  Impl& s = *this;
  const std::string& path = s.connection.path();
  // BEGIN IMMEDIATE ... COMMIT around every row of the position: the unit of
  // atomicity, and also what makes the hundred inserts fast (one journal
  // write and, with durable_commits, one fsync instead of one per row).
  const auto start = std::chrono::steady_clock::now();
  sqlite::Transaction transaction(s.connection);
  const auto [status, plan_size] = s.run_state_of(run_id);
  const std::string where =
      path + (retake_failed ? ": retake_failed_position(run " : ": append_position(run ") +
      std::to_string(run_id) + ", plan index " + std::to_string(p.plan_index) + ")";
  if (status != RunStatus::kRunning) {
    throw StoreError(where + ": the run is " + to_string(status) + ", expected running");
  }
  if (p.plan_index < 0 || p.plan_index >= plan_size) {
    throw StoreError(where + ": plan index outside the plan [0, " + std::to_string(plan_size) +
                     ")");
  }
  if (retake_failed) {
    // ON DELETE CASCADE takes its stage times, frames, detections and estimates.
    sqlite::Statement remove(s.connection,
                             "DELETE FROM positions WHERE run_id = ?1 AND plan_index = ?2 AND "
                             "status = 'failed'");
    remove.bind(1, run_id).bind(2, p.plan_index).run();
    if (sqlite3_changes(s.connection.handle()) != 1)
      throw StoreError(where +
                       ": the run has no position stored as failed at this index; "
                       "nothing written");
  }
  std::int64_t position_id = 0;
  try {
    position_id = s.write_rows(run_id, p, where);
  } catch (const DuplicatePosition&) {
    throw;
  } catch (const StoreError& e) {
    // A row the schema rejects (e.g. a rotation outside 0..3): say which
    // position, and that the transaction rolled all of it back.
    throw StoreError(where + ": nothing written: " + e.what());
  }
  if (s.record_store_time) {
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    s.insert_stage.bind(1, position_id)
        .bind(2, static_cast<std::int64_t>(p.stage_times.size()))
        .bind(3, std::string_view("store"))
        .bind(4, seconds)
        .run();
  }
  transaction.commit();
}

std::vector<std::int64_t> Store::completed_position_indices(std::int64_t run_id) const {
  impl_->run_state_of(run_id);
  sqlite::Statement select(
      impl_->connection, "SELECT plan_index FROM positions WHERE run_id = ?1 ORDER BY plan_index");
  select.bind(1, run_id);
  std::vector<std::int64_t> indices;
  while (select.step())
    indices.push_back(select.get_int64(0));
  return indices;
}

std::optional<std::int64_t> Store::first_incomplete_position(std::int64_t run_id) const {
  const std::int64_t plan_size = impl_->run_state_of(run_id).second;
  // Indices are unique per run, so walking them in order finds the first gap.
  std::int64_t expected = 0;
  for (std::int64_t index : completed_position_indices(run_id)) {
    if (index != expected) break;
    ++expected;
  }
  if (expected >= plan_size) return std::nullopt;
  return expected;
}

namespace {

constexpr const char* kPositionColumns =
    "SELECT id, plan_index, commanded_x_mm, commanded_y_mm, measured_x_mm, measured_y_mm, "
    "true_distance_m, settle_time_s, status, failure_reason, true_viewing_angle_deg, "
    "true_r00, true_r01, true_r02, true_r10, true_r11, true_r12, true_r20, true_r21, true_r22, "
    "true_tx_m, true_ty_m, true_tz_m "
    "FROM positions ";

PositionRecord read_position_row(sqlite::Statement& row) {
  PositionRecord p;
  p.plan_index = row.get_int64(1);
  p.commanded_x_mm = row.get_double(2);
  p.commanded_y_mm = row.get_double(3);
  p.measured_x_mm = row.get_optional_double(4);
  p.measured_y_mm = row.get_optional_double(5);
  p.true_distance_m = row.get_optional_double(6);
  p.settle_time_s = row.get_double(7);
  p.status = row.get_text(8) == "ok" ? PositionStatus::kOk : PositionStatus::kFailed;
  p.failure_reason = row.get_text(9);
  p.true_viewing_angle_deg = row.get_optional_double(10);
  // The pose is whole or absent (the store writes all twelve or none).
  TruePose pose;
  bool whole = true;
  for (int k = 0; k < 12 && whole; ++k) {
    const std::optional<double> v = row.get_optional_double(11 + k);
    whole = v.has_value();
    if (whole) (k < 9 ? pose.R_cam_target[k] : pose.t_cam_target_m[k - 9]) = *v;
  }
  if (whole) p.true_pose = pose;
  return p;
}

// Everything a position has besides its frames, by its row id.
class PositionDetailsReader {
 public:
  explicit PositionDetailsReader(sqlite::Connection& c)
      : stages_(c, "SELECT stage, seconds FROM stage_times WHERE position_id = ?1 ORDER BY seq"),
        bounds_(c,
                "SELECT scope, distance_sd_m_per_px FROM distance_bounds WHERE position_id = ?1 "
                "ORDER BY scope"),
        visible_(c,
                 "SELECT marker_id, side_px FROM visible_markers WHERE position_id = ?1 "
                 "ORDER BY marker_id") {}

  void read(std::int64_t position_id, PositionRecord& p) {
    stages_.bind(1, position_id);
    while (stages_.step())
      p.stage_times.push_back({stages_.get_text(0), stages_.get_double(1)});
    stages_.reset();
    bounds_.bind(1, position_id);
    while (bounds_.step())
      p.distance_bounds.push_back({bounds_.get_text(0), bounds_.get_double(1)});
    bounds_.reset();
    visible_.bind(1, position_id);
    while (visible_.step())
      p.visible_markers.push_back({visible_.get_int(0), visible_.get_double(1)});
    visible_.reset();
  }

 private:
  sqlite::Statement stages_, bounds_, visible_;
};

constexpr const char* kEstimateColumns =
    "e.solver, e.scope, e.r00, e.r01, e.r02, e.r10, e.r11, e.r12, e.r20, e.r21, e.r22, e.tx_m, "
    "e.ty_m, e.tz_m, e.distance_m, e.reprojection_error_px, e.generalization_error_px, "
    "e.iterations, e.converged, e.termination, e.time_us, e.ambiguity_ratio, e.detector";

// Reads kEstimateColumns starting at column `first`.
EstimateRecord read_estimate(const sqlite::Statement& row, int first) {
  EstimateRecord e;
  e.solver = row.get_text(first);
  e.scope = row.get_text(first + 1);
  for (int k = 0; k < 9; ++k)
    e.R_cam_target[k] = row.get_double(first + 2 + k);
  for (int k = 0; k < 3; ++k)
    e.t_cam_target_m[k] = row.get_double(first + 11 + k);
  e.distance_m = row.get_double(first + 14);
  e.reprojection_error_px = row.get_double(first + 15);
  e.generalization_error_px = row.get_optional_double(first + 16);
  e.iterations = row.get_int(first + 17);
  e.converged = row.get_int(first + 18) != 0;
  e.termination = row.get_text(first + 19);
  e.time_us = row.get_double(first + 20);
  e.ambiguity_ratio = row.get_optional_double(first + 21);
  e.detector = row.get_text(first + 22);
  return e;
}

}  // namespace

std::vector<PositionRecord> Store::positions(std::int64_t run_id) const {
  sqlite::Connection& c = impl_->connection;
  // One read transaction: a consistent snapshot while a sweep keeps appending.
  sqlite::Transaction snapshot(c, sqlite::Transaction::Kind::kRead);
  std::vector<PositionRecord> out;
  {
    sqlite::Statement select(
        c, std::string(kPositionColumns) + "WHERE run_id = ?1 ORDER BY plan_index");
    PositionDetailsReader details(c);
    select.bind(1, run_id);
    while (select.step()) {
      PositionRecord p = read_position_row(select);
      details.read(select.get_int64(0), p);
      out.push_back(std::move(p));
    }
  }
  snapshot.commit();
  return out;
}

PositionRecord Store::position(std::int64_t run_id, std::int64_t plan_index) const {
  sqlite::Connection& c = impl_->connection;
  sqlite::Transaction snapshot(c, sqlite::Transaction::Kind::kRead);
  PositionRecord p;
  {
    sqlite::Statement select(
        c, std::string(kPositionColumns) + "WHERE run_id = ?1 AND plan_index = ?2");
    select.bind(1, run_id).bind(2, plan_index);
    if (!select.step()) {
      throw StoreError(c.path() + ": run " + std::to_string(run_id) + " has no position " +
                       std::to_string(plan_index));
    }
    p = read_position_row(select);
    const std::int64_t position_id = select.get_int64(0);
    PositionDetailsReader(c).read(position_id, p);

    sqlite::Statement frames(c,
                             "SELECT id, frame_index, camera_timestamp_ns, host_timestamp_ns, "
                             "source, image_path, image_sha256 FROM frames "
                             "WHERE position_id = ?1 ORDER BY id");
    sqlite::Statement detections(
        c,
        "SELECT marker_id, rotation, a_x_px, a_y_px, b_x_px, b_y_px, c_x_px, c_y_px, d_x_px, "
        "d_y_px, contrast, bits_corrected, edge_fit_residual_px, detector, true_corner_rms_px "
        "FROM detections "
        "WHERE frame_id = ?1 ORDER BY id");
    sqlite::Statement estimates(c, std::string("SELECT ") + kEstimateColumns +
                                       " FROM estimates e WHERE e.frame_id = ?1 ORDER BY e.id");
    frames.bind(1, position_id);
    while (frames.step()) {
      FrameRecord f;
      const std::int64_t frame_id = frames.get_int64(0);
      f.index = frames.get_int(1);
      f.camera_timestamp_ns = frames.get_optional_int64(2);
      f.host_timestamp_ns = frames.get_int64(3);
      f.source = frames.get_text(4);
      f.image_path = frames.get_optional_text(5);
      f.image_sha256 = frames.get_optional_text(6);
      detections.bind(1, frame_id);
      while (detections.step()) {
        DetectionRecord d;
        d.marker_id = detections.get_int(0);
        d.rotation = detections.get_int(1);
        for (int k = 0; k < 8; ++k)
          d.corners_px[k] = detections.get_double(2 + k);
        d.contrast = detections.get_double(10);
        d.bits_corrected = detections.get_int(11);
        d.edge_fit_residual_px = detections.get_double(12);
        d.detector = detections.get_text(13);
        d.true_corner_rms_px = detections.get_optional_double(14);
        f.detections.push_back(d);
      }
      detections.reset();
      estimates.bind(1, frame_id);
      while (estimates.step())
        f.estimates.push_back(read_estimate(estimates, 0));
      estimates.reset();
      p.frames.push_back(std::move(f));
    }
  }
  snapshot.commit();
  return p;
}

std::vector<EstimateRow> Store::estimates(std::int64_t run_id, const std::string& solver) const {
  sqlite::Statement select(impl_->connection,
                           std::string("SELECT p.plan_index, f.frame_index, p.true_distance_m, ") +
                               kEstimateColumns +
                               " FROM positions p JOIN frames f ON f.position_id = p.id "
                               "JOIN estimates e ON e.frame_id = f.id "
                               "WHERE p.run_id = ?1 AND e.solver = ?2 "
                               "ORDER BY p.plan_index, f.frame_index, e.id");
  select.bind(1, run_id).bind(2, solver);
  std::vector<EstimateRow> rows;
  while (select.step()) {
    rows.push_back(EstimateRow{select.get_int64(0), select.get_int(1),
                               select.get_optional_double(2), read_estimate(select, 3)});
  }
  return rows;
}

std::vector<std::string> Store::solvers(std::int64_t run_id) const {
  sqlite::Statement select(impl_->connection,
                           "SELECT DISTINCT e.solver FROM positions p "
                           "JOIN frames f ON f.position_id = p.id "
                           "JOIN estimates e ON e.frame_id = f.id "
                           "WHERE p.run_id = ?1 ORDER BY e.solver");
  select.bind(1, run_id);
  std::vector<std::string> names;
  while (select.step())
    names.push_back(select.get_text(0));
  return names;
}

}  // namespace db::store
