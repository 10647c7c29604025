#include "report_truth.hpp"

#include <filesystem>

#include "commands.hpp"
#include "config/error.hpp"
#include "config/reader.hpp"
#include "db/store/sha256.hpp"
#include "db/store/stored_file_copy.hpp"
#include "rig/sweep/ground_truth.hpp"
#include "vision/camera.hpp"
#include "vision/rig_geometry.hpp"
#include "vision/target.hpp"

namespace rig::cli {
namespace {

// The bytes of a file the user named, for its SHA-256: BadInput naming the
// option and what the file was to be when it does not exist; read bounded by
// config::read_text_file (a folder or an oversized file is bad input).
std::string read_named_file(const std::string& option, const std::string& path) {
  const std::string what = option == "--geometry"
                               ? "a rig geometry file (rig.toml, as rig calibrate writes it)"
                               : "a camera calibration file (OpenCV YAML/XML or ROS camera_info)";
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw BadInput(option + " " + path + ": no such file; expected " + what);
  return config::read_text_file(path, option + ", " + what, config::raise_as<config::ConfigError>);
}

vision::Target stored_target(const db::store::Run& run) {
  const db::store::StoredFile& f = run.description.target_layout;
  if (f.content.empty()) return vision::Target::paper_default();
  const db::store::StoredFileCopy copy(f, "target.toml");
  return vision::Target::load(copy.path());
}

vision::Camera stored_camera(const db::store::Run& run) {
  const db::store::StoredFile& f = run.description.camera_calibration;
  if (f.content.empty()) return vision::Camera::paper_default();
  const db::store::StoredFileCopy copy(f, "camera.yaml");
  return vision::Camera::load(copy.path());
}

}  // namespace

db::report::RecomputedTruth recompute_truth(
    const TruthFiles& files, const db::store::Run& run,
    const std::vector<db::store::PositionRecord>& positions) {
  db::report::RecomputedTruth truth;
  const std::string geometry_bytes = read_named_file("--geometry", files.geometry);
  const vision::RigGeometry geometry = vision::RigGeometry::load(files.geometry);
  truth.files.push_back({"rig geometry", files.geometry, db::store::sha256_hex(geometry_bytes)});
  vision::Camera camera = vision::Camera::paper_default();
  if (files.calibration) {
    const std::string bytes = read_named_file("--calibration", *files.calibration);
    camera = vision::Camera::load(*files.calibration);
    truth.files.push_back({"camera calibration", *files.calibration, db::store::sha256_hex(bytes)});
  } else {
    camera = stored_camera(run);
    const db::store::StoredFile& f = run.description.camera_calibration;
    truth.files.push_back(
        {"camera calibration",
         (f.path.empty() ? std::string("built-in default") : f.path) + " (stored with the run)",
         f.sha256});
  }
  const vision::Target target = stored_target(run);
  for (const db::store::PositionRecord& p : positions) {
    if (!p.measured_x_mm || !p.measured_y_mm) continue;
    const sweep::GroundTruth g =
        sweep::ground_truth_at(geometry, camera, target, *p.measured_x_mm, *p.measured_y_mm);
    truth.positions[p.plan_index] = {g.distance_m, g.viewing_angle_deg, g.distance_bounds,
                                     g.visible_markers};
  }
  return truth;
}

}  // namespace rig::cli
