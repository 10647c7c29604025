// A calibration sweep of the simulated rig, in process: the hidden truth of a
// realism profile (sim::camera::draw_truth, its seed replaced), the shipped
// calibration plan and target rendered by sim::scene::SceneRenderer with the
// profile's light, optics, sensor and thin-prism lens, detected by
// vision::Detector with the nominal calibration (as a sweep detects), into the
// rig::calibrate::CalibrationProblem that `rig calibrate` reads from a run
// database. No Modbus: the read-back is the commanded position, so the
// bench's own imperfections ([bench.*] of the profile: backlash, 1 um
// repeatability, 5 ppm scale) are not part of it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rig/calibrate/calibration.hpp"
#include "sim/camera/realism.hpp"

namespace rig_test {

struct SimTruthSweep {
  std::uint64_t truth_seed = 0;
  sim::camera::SimTruth truth;
  rig::calibrate::CalibrationProblem problem;
  std::size_t frames = 0, detections = 0, markers_fully_visible = 0;
};

struct SimTruthSweepSpec {
  std::string source_dir;       // the repository (config/ is read from it)
  std::string realism = "lab";  // config/realism/<name>.toml
  std::uint64_t truth_seed = 1;
  int frames_per_position = 1;  // each with its own sensor noise
  int position_stride = 1;      // every n-th position of the plan
  // Replaces the profile's [target] bow_sag_mm when set (0: a flat sheet).
  std::optional<double> bow_sag_mm;
  // Replaces the profile's [camera_truth] radial_k4 when set (0: no r^8 term).
  std::optional<double> radial_k4;
};

// The nominal files of the simulated rig: config/sim.toml's camera (the
// paper's XC-555) and config/rigs/sim.toml.
vision::Camera sim_nominal_camera();
vision::RigGeometry sim_nominal_geometry(const std::string& source_dir);

// Renders and detects the calibration plan under the truth of spec.truth_seed.
SimTruthSweep render_calibration_sweep(const SimTruthSweepSpec& spec);

// The rotation of `estimated` relative to `truth` as a rotation vector about
// the camera axes, degrees (x pitch, y yaw, z roll).
Eigen::Vector3d camera_rotation_error_deg(const vision::RigGeometry& estimated,
                                          const vision::RigGeometry& truth);

}  // namespace rig_test
