// read_run (calibration.hpp): detections, read-backs and the stored files of a run.

#include <filesystem>
#include <fstream>

#include "config/reader.hpp"
#include "corners.hpp"
#include "db/store/store.hpp"
#include "db/store/stored_file_copy.hpp"
#include "rig/calibrate/calibration.hpp"

namespace rig::calibrate {
namespace {

db::store::Run pick_run(const db::store::Store& store, const std::string& db_path,
                        std::optional<std::int64_t> run_id) {
  const std::vector<db::store::Run> runs = store.runs();
  if (run_id) {
    for (const db::store::Run& r : runs)
      if (r.id == *run_id) return r;
    throw CalibrationInputError(db_path + ": there is no run " + std::to_string(*run_id) +
                                " (the file holds " + std::to_string(runs.size()) + " runs)");
  }
  if (runs.empty()) throw CalibrationInputError(db_path + ": the database holds no run");
  return runs.back();
}

void read_stored_files(const db::store::Run& run, CalibrationProblem* p) {
  const db::store::RunDescription& d = run.description;
  if (!d.camera_calibration.content.empty()) {
    const db::store::StoredFileCopy copy(d.camera_calibration, "camera.yaml");
    p->nominal_camera = vision::Camera::load(copy.path());
  }
  if (!d.target_layout.content.empty()) {
    const db::store::StoredFileCopy copy(d.target_layout, "target.toml");
    p->target = vision::Target::load(copy.path());
  }
  if (d.rig_geometry.content.empty())
    throw CalibrationInputError(p->source + ": the run stored no rig geometry (run_files)");
  const config::Document rig = config::Document::parse<vision::RigConfigError>(
      d.rig_geometry.content, d.rig_geometry.path + " (stored with " + p->source + ")",
      "the rig geometry");
  p->nominal_geometry = vision::RigGeometry::load(rig);
}

// The corners of the run's primary detector (RunDescription::primary_detector)
// and the frames they were found in, when the run saved them.
void add_position(const db::store::PositionRecord& position, CalibrationProblem* p) {
  const double x_mm = *position.measured_x_mm, y_mm = *position.measured_y_mm;
  for (const db::store::FrameRecord& frame : position.frames) {
    if (frame.image_path && frame.image_sha256)
      p->frames.push_back(
          {position.plan_index, x_mm, y_mm, *frame.image_path, *frame.image_sha256});
    for (const db::store::DetectionRecord& det : frame.detections) {
      if (det.detector != p->detector || !p->target.has_marker(det.marker_id)) continue;
      std::array<Eigen::Vector2d, 4> corners_px;
      for (std::size_t c = 0; c < 4; ++c)
        corners_px[c] = {det.corners_px[2 * c], det.corners_px[2 * c + 1]};
      detail::append_corners(p->target, position.plan_index, x_mm, y_mm, det.marker_id, corners_px,
                             &p->corners);
    }
  }
}

}  // namespace

CalibrationProblem read_run(const std::string& db_path, std::optional<std::int64_t> run_id) {
  if (!std::filesystem::is_regular_file(db_path))
    throw CalibrationInputError(db_path + ": no such run database (expected a file written by " +
                                "rig sweep)");
  db::store::StoreOptions options;
  options.read_only = true;
  std::optional<db::store::Store> store;
  try {
    store.emplace(db_path, options);
  } catch (const db::store::StoreError& e) {
    throw CalibrationInputError(std::string("not a readable run database: ") + e.what());
  }
  const db::store::Run run = pick_run(*store, db_path, run_id);
  CalibrationProblem p;
  p.source = db_path + ":" + std::to_string(run.id);
  read_stored_files(run, &p);
  p.detector = run.description.primary_detector;
  for (const std::int64_t index : store->completed_position_indices(run.id)) {
    const db::store::PositionRecord position = store->position(run.id, index);
    if (position.status != db::store::PositionStatus::kOk || !position.measured_x_mm ||
        !position.measured_y_mm)
      continue;
    add_position(position, &p);
  }
  if (p.corners.empty())
    throw CalibrationInputError(p.source + ": the run has no detections of the layout's markers " +
                                "at positions with a bench read-back; nothing to calibrate from");
  return p;
}

}  // namespace rig::calibrate
