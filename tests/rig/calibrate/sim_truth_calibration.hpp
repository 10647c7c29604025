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
  double radial_k4 = 0;  // the rendered lens's r^8 term (SceneOptions::radial_k4)
  // The corners as the sweep's detector found them through the nominal camera;
  // problem.frames lists the rendered frames (no file: images holds them).
  rig::calibrate::CalibrationProblem problem;
  std::vector<cv::Mat> images;  // the rendered frames, in problem.frames' order
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

// The true lens in the 5-coefficient model a calibration fits (Brown-Conrady
// k1 k2 p1 p2 k3; no thin prism, no r^8). To first order a thin prism is a
// small rotation of the camera: a yaw by theta moves a normalised point by
// theta (1 + x^2, x y) = theta (1, 0) + (theta / 2) (r^2 + 2 x^2, 2 x y) -
// (theta / 2) (r^2, 0), i.e. cx moved by fx theta, p2 by theta / 2 and a
// prism s1 = -theta / 2 (likewise the pitch with cy, p1 and s3). So a model
// without a prism describes such a lens as a camera turned by about 2 |s|
// radians, and no calibration with that model can find the mechanical
// rotation: the images are the same. `camera` and
// `rotation_deg` are that description, the intrinsics, distortion and
// rotation of the model's camera frame relative to the true one (rotation
// vector about the camera axes, degrees: x pitch, y yaw, z roll) that best
// reproduce the true projection over the image, by least squares on a
// 48 x 36 grid of image points, noise-free; `rms_px` is what the model cannot
// hold (mostly the r^8 term's remainder).
struct LensInModel {
  vision::Camera camera;
  Eigen::Vector3d rotation_deg;
  double rms_px = 0;
};
LensInModel lens_in_five_coefficients(const SimTruthSweep& sweep);

// The true rig geometry with the camera frame of `lens`: the camera turned by
// lens.rotation_deg about its centre.
vision::RigGeometry geometry_in_model(const vision::RigGeometry& truth, const LensInModel& lens);

// The sweep's problem with its corners detected again in its rendered frames
// through `camera`, by rig::calibrate::detect_corners (what `rig calibrate`
// does with a run's saved frames, rig::calibrate::redetected).
rig::calibrate::CalibrationProblem redetected(const SimTruthSweep& sweep,
                                              const vision::Camera& camera);

// The sweep as `rig sweep` with [capture] save_frames records it: a run in
// the database at db_path (the nominal calibration, the calibration layout
// and config/rigs/sim.toml stored; the read-backs, the detections) whose
// frames are PNG files in frames_dir with their SHA-256. Returns the run id.
std::int64_t write_sim_truth_run(const SimTruthSweep& sweep, const std::string& source_dir,
                                 const std::string& db_path, const std::string& frames_dir);

// The rotation of `estimated` relative to `truth` as a rotation vector about
// the camera axes, degrees (x pitch, y yaw, z roll).
Eigen::Vector3d camera_rotation_error_deg(const vision::RigGeometry& estimated,
                                          const vision::RigGeometry& truth);

}  // namespace rig_test
