// db::store::Store: opening the file and the runs table (start, finish, resume, read).
#include <filesystem>
#include <nlohmann/json.hpp>

#include "db/store/sha256.hpp"
#include "db/store/store.hpp"
#include "schema.hpp"
#include "store_impl.hpp"

namespace db::store {
namespace {

// UTC now as ISO 8601 with milliseconds, from SQLite so that every time in the
// file comes from one clock and one format.
constexpr const char* kNow = "strftime('%Y-%m-%dT%H:%M:%fZ', 'now')";

struct FileRole {
  const char* role;
  StoredFile RunDescription::*file;
};
constexpr FileRole kFileRoles[] = {
    {"sweep_file", &RunDescription::sweep_file},
    {"camera_calibration", &RunDescription::camera_calibration},
    {"target_layout", &RunDescription::target_layout},
    {"rig_geometry", &RunDescription::rig_geometry},
    {"bench_profile", &RunDescription::bench_profile},
};

void require_json(const std::string& path, const char* field, const std::string& text,
                  bool must_be_object) {
  const auto parsed = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (parsed.is_discarded()) {
    throw StoreError(path + ": start_run: " + field + " is not valid JSON: \"" +
                     text.substr(0, 80) + "\"");
  }
  if (must_be_object && !parsed.is_object()) {
    throw StoreError(path + ": start_run: " + field + " must be a JSON object, got \"" +
                     text.substr(0, 80) + "\"");
  }
}

}  // namespace

RunStatus run_status_from_text(const std::string& path, const std::string& text) {
  for (RunStatus s :
       {RunStatus::kRunning, RunStatus::kCompleted, RunStatus::kAborted, RunStatus::kFailed}) {
    if (text == to_string(s)) return s;
  }
  throw StoreError(path + ": unknown run status \"" + text + "\" in table runs");
}

std::string sqlite_library_version() {
  return sqlite3_libversion();
}

namespace {

// A report must never create a file where the user mistyped a path.
const std::string& existing_file(const std::string& path, bool read_only) {
  if (read_only && !std::filesystem::is_regular_file(path)) {
    throw StoreError(path + ": no such file; expected a rig run database (written by rig sweep)");
  }
  return path;
}

}  // namespace

// NOMUTEX: a Store is used from one thread at a time (store.hpp), so SQLite
// need not lock the connection around every call; its serialized mode's
// mutex took a sixth of append_position's time (bench_sweep
// BM_EstimateInsertRate under perf).
Store::Impl::Impl(const std::string& path, bool read_only)
    : connection(existing_file(path, read_only),
                 (read_only ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE) |
                     SQLITE_OPEN_NOMUTEX) {}

void Store::Impl::prepare_writers() {
  run_state =
      sqlite::Statement(connection, "SELECT status, plan_size FROM runs WHERE id = ?1", true);
  insert_position = sqlite::Statement(
      connection,
      "INSERT INTO positions (run_id, plan_index, commanded_x_mm, commanded_y_mm, measured_x_mm, "
      "measured_y_mm, true_distance_m, settle_time_s, status, failure_reason, "
      "true_viewing_angle_deg, true_r00, true_r01, true_r02, true_r10, true_r11, true_r12, "
      "true_r20, true_r21, true_r22, true_tx_m, true_ty_m, true_tz_m) VALUES (?1, ?2, ?3, ?4, "
      "?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18, ?19, ?20, ?21, ?22, ?23)",
      true);
  insert_bound = sqlite::Statement(
      connection,
      "INSERT INTO distance_bounds (position_id, scope, distance_sd_m_per_px) VALUES (?1, ?2, ?3)",
      true);
  insert_visible = sqlite::Statement(
      connection,
      "INSERT INTO visible_markers (position_id, marker_id, side_px) VALUES (?1, ?2, ?3)", true);
  insert_stage = sqlite::Statement(
      connection,
      "INSERT INTO stage_times (position_id, seq, stage, seconds) VALUES (?1, ?2, ?3, ?4)", true);
  insert_frame = sqlite::Statement(
      connection,
      "INSERT INTO frames (position_id, frame_index, camera_timestamp_ns, host_timestamp_ns, "
      "source, image_path, image_sha256) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
      true);
  insert_detection = sqlite::Statement(
      connection,
      "INSERT INTO detections (frame_id, marker_id, rotation, a_x_px, a_y_px, b_x_px, b_y_px, "
      "c_x_px, c_y_px, d_x_px, d_y_px, contrast, bits_corrected, edge_fit_residual_px, detector, "
      "true_corner_rms_px) "
      "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16)",
      true);
  insert_estimate = sqlite::Statement(
      connection,
      "INSERT INTO estimates (frame_id, solver, scope, r00, r01, r02, r10, r11, r12, r20, r21, "
      "r22, tx_m, ty_m, tz_m, distance_m, reprojection_error_px, generalization_error_px, "
      "iterations, converged, termination, time_us, ambiguity_ratio, detector) VALUES (?1, ?2, "
      "?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18, ?19, ?20, ?21, "
      "?22, ?23, ?24)",
      true);
}

std::pair<RunStatus, std::int64_t> Store::Impl::run_state_of(std::int64_t run_id) {
  run_state.bind(1, run_id);
  if (!run_state.step()) {
    run_state.reset();
    throw StoreError(connection.path() + ": no run with id " + std::to_string(run_id));
  }
  const auto state = std::make_pair(run_status_from_text(connection.path(), run_state.get_text(0)),
                                    run_state.get_int64(1));
  run_state.reset();
  return state;
}

Store::Store(const std::string& path, StoreOptions options)
    : impl_(std::make_unique<Impl>(path, options.read_only)) {
  schema::open_and_migrate(impl_->connection, options);
  impl_->record_store_time = options.record_store_time;
  impl_->prepare_writers();
}

Store::~Store() = default;
Store::Store(Store&&) noexcept = default;
Store& Store::operator=(Store&&) noexcept = default;

const std::string& Store::path() const {
  return impl_->connection.path();
}

std::int64_t Store::start_run(RunDescription d) {
  const std::string& path = impl_->connection.path();
  require_json(path, "config_json", d.config_json, false);
  require_json(path, "plan_json", d.plan_json, false);
  require_json(path, "library_versions_json", d.library_versions_json, true);
  if (d.plan_size < 0) {
    throw StoreError(path + ": start_run: plan_size is " + std::to_string(d.plan_size) +
                     ", expected 0 or more");
  }
  sqlite::Transaction transaction(impl_->connection);
  sqlite::Statement insert(
      impl_->connection,
      std::string("INSERT INTO runs (started_at, status, config_json, plan_json, plan_size, "
                  "software_version, library_versions_json, host, primary_detector) VALUES (") +
          kNow + ", 'running', ?1, ?2, ?3, ?4, ?5, ?6, ?7)");
  insert.bind(1, d.config_json)
      .bind(2, d.plan_json)
      .bind(3, d.plan_size)
      .bind(4, d.software_version)
      .bind(5, d.library_versions_json)
      .bind(6, d.host)
      .bind(7, d.primary_detector)
      .run();
  const std::int64_t run_id = impl_->connection.last_insert_rowid();
  sqlite::Statement insert_file(
      impl_->connection,
      "INSERT INTO run_files (run_id, role, path, content, sha256) VALUES (?1, ?2, ?3, ?4, ?5)");
  for (const FileRole& role : kFileRoles) {
    const StoredFile& file = d.*role.file;
    insert_file.bind(1, run_id)
        .bind(2, std::string_view(role.role))
        .bind(3, file.path)
        .bind_blob(4, file.content)
        .bind(5, sha256_hex(file.content))
        .run();
  }
  transaction.commit();
  return run_id;
}

void Store::finish_run(std::int64_t run_id, RunStatus status, const std::string& reason) {
  const std::string& path = impl_->connection.path();
  if (status == RunStatus::kRunning) {
    throw StoreError(path + ": finish_run(" + std::to_string(run_id) +
                     "): status must be completed, aborted or failed, got running");
  }
  if (status != RunStatus::kCompleted && reason.empty()) {
    throw StoreError(path + ": finish_run(" + std::to_string(run_id) + ", " + to_string(status) +
                     "): a reason is required");
  }
  sqlite::Transaction transaction(impl_->connection);
  const RunStatus current = impl_->run_state_of(run_id).first;
  if (current != RunStatus::kRunning) {
    throw StoreError(path + ": finish_run(" + std::to_string(run_id) + ", " + to_string(status) +
                     "): the run is " + to_string(current) + ", expected running");
  }
  sqlite::Statement update(impl_->connection,
                           std::string("UPDATE runs SET status = ?1, status_reason = ?2, "
                                       "ended_at = ") +
                               kNow + " WHERE id = ?3");
  update.bind(1, std::string_view(to_string(status))).bind(2, reason).bind(3, run_id).run();
  transaction.commit();
}

void Store::resume_run(std::int64_t run_id, bool completed_with_failed) {
  sqlite::Transaction transaction(impl_->connection);
  const RunStatus current = impl_->run_state_of(run_id).first;
  bool has_failed = false;
  if (current == RunStatus::kCompleted && completed_with_failed) {
    sqlite::Statement failed(impl_->connection,
                             "SELECT 1 FROM positions WHERE run_id = ?1 AND status = 'failed' "
                             "LIMIT 1");
    has_failed = failed.bind(1, run_id).step();
  }
  if (current == RunStatus::kCompleted && !has_failed) {
    throw StoreError(impl_->connection.path() + ": resume_run(" + std::to_string(run_id) +
                     "): the run is completed; there is nothing to resume");
  }
  sqlite::Statement update(impl_->connection,
                           "UPDATE runs SET status = 'running', status_reason = '', "
                           "ended_at = NULL WHERE id = ?1");
  update.bind(1, run_id).run();
  transaction.commit();
}

void Store::record_camera(std::int64_t run_id, const RunCamera& c) {
  sqlite::Transaction transaction(impl_->connection);
  impl_->run_state_of(run_id);
  sqlite::Statement insert(impl_->connection,
                           "INSERT OR REPLACE INTO run_camera (run_id, source, device_id, vendor, "
                           "model, serial, device_version) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)");
  insert.bind(1, run_id)
      .bind(2, c.source)
      .bind(3, c.device_id)
      .bind(4, c.vendor)
      .bind(5, c.model)
      .bind(6, c.serial)
      .bind(7, c.device_version)
      .run();
  transaction.commit();
}

void Store::record_event(std::int64_t run_id, const std::string& kind, const std::string& message,
                         std::optional<std::int64_t> plan_index) {
  const std::string& path = impl_->connection.path();
  if (kind.empty()) {
    throw StoreError(path + ": record_event(run " + std::to_string(run_id) +
                     "): kind is empty; expected e.g. \"alarm\" or \"pause\"");
  }
  sqlite::Transaction transaction(impl_->connection);
  impl_->run_state_of(run_id);
  sqlite::Statement insert(impl_->connection,
                           std::string("INSERT INTO run_events (run_id, at, plan_index, kind, "
                                       "message) VALUES (?1, ") +
                               kNow + ", ?2, ?3, ?4)");
  insert.bind(1, run_id).bind(2, plan_index).bind(3, kind).bind(4, message).run();
  transaction.commit();
}

std::vector<RunEvent> Store::events(std::int64_t run_id) const {
  impl_->run_state_of(run_id);
  sqlite::Statement select(impl_->connection,
                           "SELECT at, plan_index, kind, message FROM run_events "
                           "WHERE run_id = ?1 ORDER BY id");
  select.bind(1, run_id);
  std::vector<RunEvent> events;
  while (select.step()) {
    events.push_back(RunEvent{select.get_text(0), select.get_optional_int64(1), select.get_text(2),
                              select.get_text(3)});
  }
  return events;
}

namespace {

std::vector<Run> read_runs(sqlite::Connection& connection, std::optional<std::int64_t> only) {
  sqlite::Statement select(
      connection,
      std::string("SELECT id, started_at, ended_at, status, status_reason, config_json, "
                  "plan_json, plan_size, software_version, library_versions_json, host, "
                  "primary_detector FROM runs ") +
          (only ? "WHERE id = ?1 " : "") + "ORDER BY id");
  if (only) select.bind(1, *only);
  sqlite::Statement files(connection,
                          "SELECT role, path, content, sha256 FROM run_files WHERE run_id = ?1");
  sqlite::Statement camera(connection,
                           "SELECT source, device_id, vendor, model, serial, device_version "
                           "FROM run_camera WHERE run_id = ?1");
  std::vector<Run> runs;
  while (select.step()) {
    Run run;
    run.id = select.get_int64(0);
    run.started_at = select.get_text(1);
    run.ended_at = select.get_optional_text(2);
    run.status = run_status_from_text(connection.path(), select.get_text(3));
    run.status_reason = select.get_text(4);
    RunDescription& d = run.description;
    d.config_json = select.get_text(5);
    d.plan_json = select.get_text(6);
    d.plan_size = select.get_int64(7);
    d.software_version = select.get_text(8);
    d.library_versions_json = select.get_text(9);
    d.host = select.get_text(10);
    d.primary_detector = select.get_text(11);
    files.bind(1, run.id);
    while (files.step()) {
      const std::string role = files.get_text(0);
      for (const FileRole& r : kFileRoles) {
        if (role == r.role)
          d.*r.file = StoredFile{files.get_text(1), files.get_blob(2), files.get_text(3)};
      }
    }
    files.reset();
    camera.bind(1, run.id);
    if (camera.step()) {
      run.camera = RunCamera{camera.get_text(0), camera.get_text(1), camera.get_text(2),
                             camera.get_text(3), camera.get_text(4), camera.get_text(5)};
    }
    camera.reset();
    runs.push_back(std::move(run));
  }
  return runs;
}

}  // namespace

std::vector<Run> Store::runs() const {
  return read_runs(impl_->connection, std::nullopt);
}

Run Store::run(std::int64_t run_id) const {
  std::vector<Run> found = read_runs(impl_->connection, run_id);
  if (found.empty()) {
    throw StoreError(impl_->connection.path() + ": no run with id " + std::to_string(run_id));
  }
  return std::move(found.front());
}

}  // namespace db::store
