#include "synthetic_calibration.hpp"

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include "db/store/store.hpp"

namespace rig_test {

vision::Camera calibration_true_camera() {
  const vision::Camera n = vision::Camera::paper_default();
  const vision::Intrinsics& k = n.intrinsics();
  return vision::Camera({k.fx * 1.01, k.fy * 1.006, k.cx + 3.0, k.cy - 2.0},
                        {-0.2150, 0.1300, -0.0004, 0.0009, 0.0}, n.width_px(), n.height_px());
}

vision::RigGeometry calibration_true_geometry() {
  return vision::RigGeometry::from_mount({5.0, -3.0, 2.0}, {0.3, -0.2, 0.25}, {1002.0, 148.5, 3.0},
                                         {1.0, -1.5, 0.2});
}

std::string calibration_nominal_rig_toml() {
  return "[camera_mount]\noffset_mm = [0.0, 0.0, 0.0]\nmisalignment_deg = [0.0, 0.0, 0.0]\n"
         "[target]\norigin_mm = [1000.0, 150.0, 0.0]\ntilt_deg = [0.0, 0.0, 0.0]\n";
}

std::vector<std::pair<double, double>> read_csv_plan(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot be read");
  std::vector<std::pair<double, double>> plan;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("x_mm", 0) == 0) continue;
    const std::size_t comma = line.find(',');
    plan.emplace_back(std::stod(line.substr(0, comma)), std::stod(line.substr(comma + 1)));
  }
  return plan;
}

std::string calibration_plan_path(const std::string& source_dir) {
  return source_dir + "/config/plans/calibration.csv";
}

std::string calibration_target_path(const std::string& source_dir) {
  return source_dir + "/config/targets/calibration.toml";
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  if (!in) throw std::runtime_error(path + ": cannot be read");
  return s.str();
}

std::string camera_yaml(const vision::Camera& camera) {
  const vision::Intrinsics& k = camera.intrinsics();
  const vision::Distortion& d = camera.distortion();
  std::ostringstream s;
  s.precision(17);
  s << "image_width: " << camera.width_px() << "\nimage_height: " << camera.height_px()
    << "\ncamera_matrix: {rows: 3, cols: 3, data: [" << k.fx << ", 0, " << k.cx << ", 0, " << k.fy
    << ", " << k.cy << ", 0, 0, 1]}\ndistortion_model: plumb_bob\n"
    << "distortion_coefficients: {rows: 1, cols: 5, data: [" << d.k1 << ", " << d.k2 << ", " << d.p1
    << ", " << d.p2 << ", " << d.k3 << "]}\n";
  return s.str();
}

namespace {

// The detections of every marker whose four corners fall inside the image.
std::vector<db::store::DetectionRecord> detect(const SyntheticCalibrationSpec& spec,
                                               const vision::Target& target, double x_mm,
                                               double y_mm, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, spec.corner_noise_px);
  const vision::Pose T = spec.true_geometry.T_cam_target(x_mm, y_mm);
  const vision::Camera& cam = spec.true_camera;
  std::vector<db::store::DetectionRecord> detections;
  for (const vision::TargetMarker& m : target.markers) {
    db::store::DetectionRecord d;
    d.marker_id = m.id;
    bool inside = true;
    const auto corners = target.corners_m(m);
    for (std::size_t c = 0; c < 4; ++c) {
      const Eigen::Vector3d p = T.R * corners[c] + T.t;
      if (p.z() <= 0) {
        inside = false;
        break;
      }
      const Eigen::Vector2d px = cam.project(p);
      inside = inside && px.x() >= 0 && px.y() >= 0 && px.x() <= cam.width_px() - 1 &&
               px.y() <= cam.height_px() - 1;
      d.corners_px[2 * c] = px.x() + noise(rng);
      d.corners_px[2 * c + 1] = px.y() + noise(rng);
    }
    if (inside) detections.push_back(d);
  }
  return detections;
}

}  // namespace

db::store::RunDescription calibration_run_description(const vision::Camera& nominal_camera,
                                                      const std::string& layout_path,
                                                      const std::string& rig_path,
                                                      const std::string& rig_toml,
                                                      std::int64_t plan_size) {
  db::store::RunDescription d;
  d.config_json = "{}";
  d.plan_json = "{}";
  d.plan_size = plan_size;
  d.camera_calibration = {"camera.yaml", camera_yaml(nominal_camera), ""};
  if (!layout_path.empty()) d.target_layout = {layout_path, read_file(layout_path), ""};
  d.rig_geometry = {rig_path, rig_toml, ""};
  d.software_version = "test";
  d.library_versions_json = "{}";
  d.host = "test";
  return d;
}

std::int64_t write_calibration_run(const std::string& path, const SyntheticCalibrationSpec& spec) {
  db::store::StoreOptions options;
  options.durable_commits = false;
  db::store::Store store(path, options);
  const std::int64_t run = store.start_run(calibration_run_description(
      spec.nominal_camera, spec.target_layout_path, "rig.toml", spec.nominal_rig_toml,
      static_cast<std::int64_t>(spec.plan.size())));
  const vision::Target target = spec.target_layout_path.empty()
                                    ? vision::Target::paper_default()
                                    : vision::Target::load(spec.target_layout_path);
  std::mt19937_64 rng(spec.seed);
  for (std::size_t i = 0; i < spec.plan.size(); ++i) {
    db::store::PositionRecord p;
    p.plan_index = static_cast<std::int64_t>(i);
    p.commanded_x_mm = spec.plan[i].first;
    p.commanded_y_mm = spec.plan[i].second;
    p.measured_x_mm = p.commanded_x_mm;
    p.measured_y_mm = p.commanded_y_mm;
    for (int f = 0; f < spec.frames_per_position; ++f) {
      db::store::FrameRecord frame;
      frame.index = f;
      frame.source = "synthetic";
      frame.detections = detect(spec, target, p.commanded_x_mm, p.commanded_y_mm, rng);
      p.frames.push_back(frame);
    }
    store.append_position(run, p);
  }
  store.finish_run(run, db::store::RunStatus::kCompleted, "");
  return run;
}

}  // namespace rig_test
