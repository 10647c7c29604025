// A synthetic calibration sweep written through db::store::Store into a real
// SQLite file: a known true camera and rig geometry, the paper's target, the
// corners of every marker fully inside the image projected through
// vision::Camera at each plan position's read-back, plus seeded Gaussian
// corner noise. The run stores the nominal calibration and rig geometry that
// rig calibrate starts from.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "db/store/records.hpp"
#include "vision/camera.hpp"
#include "vision/rig_geometry.hpp"
#include "vision/target.hpp"

namespace rig_test {

struct SyntheticCalibrationSpec {
  vision::Camera true_camera = vision::Camera::paper_default();
  vision::RigGeometry true_geometry;
  vision::Camera nominal_camera = vision::Camera::paper_default();
  std::string nominal_rig_toml;  // the rig file the run stores
  // The layout file the corners are projected from and the run stores
  // (empty: the paper's sheet, stored as the built-in default).
  std::string target_layout_path;
  std::vector<std::pair<double, double>> plan;  // read-backs, mm
  double corner_noise_px = 0.1;                 // sd per coordinate
  int frames_per_position = 1;                  // each with its own noise
  std::uint64_t seed = 1;
};

// The true camera of the calibration tests: the paper's Sony XC-555 with fx
// 1 % and fy 0.6 % off, the principal point moved (+3, -2) px, k1, k2 and the
// tangential terms changed.
vision::Camera calibration_true_camera();
// The true geometry: mount misalignment (0.3, -0.2, 0.25) deg, camera offset
// (5, -3, 2) mm, target origin (1002, 148.5, 3) mm, tilt (1.0, -1.5, 0.2) deg.
vision::RigGeometry calibration_true_geometry();
// The nominal (hand-measured) rig file: no misalignment, no tilt, offset 0,
// origin (1000, 150, 0) mm.
std::string calibration_nominal_rig_toml();

// The positions of a CSV plan file (x_mm,y_mm lines, '#' comments, a header).
std::vector<std::pair<double, double>> read_csv_plan(const std::string& path);

// The shipped calibration plan and calibration target (config/plans/calibration.csv,
// config/targets/calibration.toml), paths under source_dir.
std::string calibration_plan_path(const std::string& source_dir);
std::string calibration_target_path(const std::string& source_dir);

// The bytes of a file (std::runtime_error naming it when it cannot be read).
std::string read_file(const std::string& path);
// The camera as a ROS camera_info file (plumb_bob), as a run stores it.
std::string camera_yaml(const vision::Camera& camera);

// A calibration run's description: the nominal camera, the layout file
// (empty: the built-in paper sheet) and the rig file stored, the rest
// placeholders.
db::store::RunDescription calibration_run_description(const vision::Camera& nominal_camera,
                                                      const std::string& layout_path,
                                                      const std::string& rig_path,
                                                      const std::string& rig_toml,
                                                      std::int64_t plan_size);

// Appends a run to the database at path; returns its id.
std::int64_t write_calibration_run(const std::string& path, const SyntheticCalibrationSpec& spec);

}  // namespace rig_test
