// write_calibration (calibration.hpp): the calibrated camera and geometry in
// the formats rig reads, and calibration.json with the statistics.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "model.hpp"
#include "rig/calibrate/calibration.hpp"

namespace rig::calibrate {
namespace {

void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error(path + ": cannot be written");
}

std::string number(double v) {
  std::ostringstream s;
  s << std::setprecision(12) << v;
  return s.str();
}

std::string triple(double a, double b, double c) {
  return "[" + number(a) + ", " + number(b) + ", " + number(c) + "]";
}

// The ROS camera_info YAML that vision::Camera::load reads: plumb_bob (5
// coefficients), or with a thin prism OpenCV's 12 (k4..k6 = 0) under
// rational_polynomial, the ROS model whose coefficients go to OpenCV as they
// are (ROS defines it with 8; a reader that takes only 8 drops s1..s4).
std::string ros_camera_info(const vision::Camera& camera) {
  const vision::Intrinsics& k = camera.intrinsics();
  const cv::Mat d = camera.distortion_cv();
  std::ostringstream s;
  s << "image_width: " << camera.width_px() << "\nimage_height: " << camera.height_px()
    << "\ncamera_matrix: {rows: 3, cols: 3, data: [" << number(k.fx) << ", 0, " << number(k.cx)
    << ", 0, " << number(k.fy) << ", " << number(k.cy) << ", 0, 0, 1]}\n";
  if (camera.distortion().has_thin_prism())
    s << "# k1 k2 p1 p2 k3 k4 k5 k6 s1 s2 s3 s4 (OpenCV's order; s1..s4 thin prism)\n"
      << "distortion_model: rational_polynomial\n";
  else
    s << "distortion_model: plumb_bob\n";
  s << "distortion_coefficients: {rows: 1, cols: " << d.cols << ", data: [";
  for (int i = 0; i < d.cols; ++i)
    s << (i ? ", " : "") << number(d.at<double>(0, i));
  s << "]}\n";
  return s.str();
}

// The rig geometry file: the nominal camera offset, the target origin at
// offset + d (calibration.hpp).
std::string rig_file(const CalibrationProblem& problem, const CalibrationResult& r) {
  const auto v = [&](int i) { return r.parameters[static_cast<std::size_t>(i)].value; };
  const Eigen::Vector3d offset_mm = problem.nominal_geometry.T_carriage_cam.t * 1000.0;
  using detail::kMisalignment, detail::kOffset, detail::kTilt;
  const Eigen::Vector3d origin_mm =
      offset_mm + Eigen::Vector3d(v(kOffset), v(kOffset + 1), v(kOffset + 2));
  std::ostringstream s;
  s << "# Calibrated by rig calibrate from "
    << std::filesystem::path(problem.source).filename().string()
    << ".\n# With translation-only motion only origin - offset is observable: the camera\n"
    << "# offset is the nominal one, the target origin absorbs the difference.\n"
    << "[camera_mount]\noffset_mm = " << triple(offset_mm.x(), offset_mm.y(), offset_mm.z())
    << "\nmisalignment_deg = "
    << triple(v(kMisalignment), v(kMisalignment + 1), v(kMisalignment + 2))
    << "\n\n[target]\norigin_mm = " << triple(origin_mm.x(), origin_mm.y(), origin_mm.z())
    << "\ntilt_deg = " << triple(v(kTilt), v(kTilt + 1), v(kTilt + 2)) << "\n";
  return s.str();
}

nlohmann::json statistics(const CalibrationProblem& problem, const CalibrationResult& r,
                          const HeldOutCheck& held_out) {
  nlohmann::json j;
  j["source"] = std::filesystem::path(problem.source).filename().string();
  j["corners"] = r.corners;
  j["corners_from"] = problem.corners_from;
  j["iterations"] = r.iterations;
  j["solve_seconds"] = r.solve_seconds;
  j["sigma_px"] = r.sigma_px;
  j["sd_method"] = r.sd_method;
  j["rms_px"] = r.rms_px;
  j["termination"] = r.termination;
  nlohmann::json params = nlohmann::json::array();
  std::vector<std::string> names;
  for (const ParameterEstimate& e : r.parameters) {
    params.push_back({{"name", e.name},
                      {"unit", e.unit},
                      {"value", e.value},
                      {"sd", e.sd},
                      {"sd_if_corners_independent", e.sd_independent},
                      {"fixed", e.fixed}});
    names.push_back(e.name);
  }
  j["parameters"] = params;
  nlohmann::json rows = nlohmann::json::array();
  for (int i = 0; i < r.correlation.rows(); ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (int k = 0; k < r.correlation.cols(); ++k)
      row.push_back(r.correlation(i, k));
    rows.push_back(row);
  }
  j["correlation"] = {{"names", names}, {"matrix", rows}};
  nlohmann::json positions = nlohmann::json::array(), markers = nlohmann::json::array();
  for (const auto& [index, rms] : r.rms_by_position_px)
    positions.push_back({{"plan_index", index}, {"rms_px", rms}});
  for (const auto& [id, rms] : r.rms_by_marker_px)
    markers.push_back({{"marker_id", id}, {"rms_px", rms}});
  j["rms_by_position"] = positions;
  j["rms_by_marker"] = markers;
  j["held_out"] = {{"rule", "fit on even plan indices, predict odd ones from the read-backs"},
                   {"fit_positions", held_out.fit_positions},
                   {"held_out_positions", held_out.held_out_positions},
                   {"fit_rms_px", held_out.fit_rms_px},
                   {"held_out_rms_px", held_out.held_out_rms_px}};
  return j;
}

}  // namespace

CalibrationFiles write_calibration(const std::string& out_dir, const CalibrationProblem& problem,
                                   const CalibrationResult& result, const HeldOutCheck& held_out) {
  std::error_code error;
  std::filesystem::create_directories(out_dir, error);
  if (error) throw std::runtime_error(out_dir + ": cannot create the folder: " + error.message());
  const std::filesystem::path dir(out_dir);
  CalibrationFiles files{(dir / "camera.yaml").string(), (dir / "camera_info.yaml").string(),
                         (dir / "rig.toml").string(), (dir / "calibration.json").string()};
  result.camera.save(files.opencv);
  write_text(files.ros, ros_camera_info(result.camera));
  write_text(files.rig, rig_file(problem, result));
  write_text(files.json, statistics(problem, result, held_out).dump(2) + "\n");
  return files;
}

}  // namespace rig::calibrate
