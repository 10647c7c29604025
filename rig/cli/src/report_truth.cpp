#include "report_truth.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "commands.hpp"
#include "db/store/sha256.hpp"
#include "rig/sweep/ground_truth.hpp"
#include "vision/camera.hpp"
#include "vision/rig_geometry.hpp"
#include "vision/target.hpp"

namespace rig::cli {
namespace {

// The bytes of a file the user named, for its SHA-256; BadInput naming the
// option and the file when it cannot be read.
std::string read_named_file(const std::string& option, const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw BadInput(option + " " + path + ": no such file; expected " +
                   (option == "--geometry" ? "a rig geometry file (rig.toml, as rig calibrate "
                                             "writes it)"
                                           : "a camera calibration file (OpenCV YAML/XML or ROS "
                                             "camera_info)"));
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (!in) throw BadInput(option + " " + path + ": cannot be read");
  return bytes.str();
}

// A stored file of the run, written to a private temporary folder for the
// loaders that take a path; removed when done.
class StoredCopy {
 public:
  StoredCopy(const db::store::StoredFile& file, const std::string& name) {
    std::string pattern = (std::filesystem::temp_directory_path() / "rig-report-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr)
      throw std::runtime_error("cannot create a temporary folder for the run's stored " + name);
    dir_ = pattern;
    const std::string stem = std::filesystem::path(file.path).filename().string();
    path_ = (dir_ / (stem.empty() ? name : stem)).string();
    std::ofstream out(path_, std::ios::binary);
    out << file.content;
    if (!out) throw std::runtime_error("cannot write " + path_);
  }
  ~StoredCopy() {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  StoredCopy(const StoredCopy&) = delete;
  StoredCopy& operator=(const StoredCopy&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::filesystem::path dir_;
  std::string path_;
};

vision::Target stored_target(const db::store::Run& run) {
  const db::store::StoredFile& f = run.description.target_layout;
  if (f.content.empty()) return vision::Target::paper_default();
  const StoredCopy copy(f, "target.toml");
  return vision::Target::load(copy.path());
}

vision::Camera stored_camera(const db::store::Run& run) {
  const db::store::StoredFile& f = run.description.camera_calibration;
  if (f.content.empty()) return vision::Camera::paper_default();
  const StoredCopy copy(f, "camera.yaml");
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
