// The simulated rig's file (config/sim.toml): which bench, which camera, which
// target and geometry `rig sim --config FILE` runs. Paths in it are relative
// to the file's folder.
//
//   [bench]
//   config = "benches/sim.toml"       # the bench's drive profile and [sim] table
//   host = "127.0.0.1"                # Modbus TCP listening address
//   port = 1502                       # 0: a free port (printed)
//   [camera]
//   rig = "rigs/sim.toml"             # geometry (vision/rig_geometry.hpp)
//   target = "targets/paper.toml"     # printed sheet (vision/target.hpp)
//   calibration = ""                  # OpenCV/ROS calibration; "" = the paper's XC-555
//   address = "127.0.0.1"             # GigE Vision interface address
//   serial = "RIGSIM01"               # device id "rig-rig-sim-RIGSIM01"
//   trigger_poll_hz = 1000            # see sim::camera::CameraServerOptions
//   nominal_exposure_us = 10000
//   seed = 1
//   genicam = "sfnc"                  # feature names: "sfnc" (ExposureTime) | "legacy"
//   (ExposureTimeAbs) [realism] profile = "realism/lab.toml"      # sim/camera/realism.hpp; absent:
//   the ideal world
// Every path must name an existing file; a key or table not listed is refused.
#pragma once

#include <memory>
#include <string>

#include "config/error.hpp"
#include "sim/camera/realism.hpp"
#include "sim/camera/server.hpp"

namespace sim::camera {

// A simulated rig file that cannot be read, lacks a key, holds an unknown key
// or a malformed value, or names a file that does not exist. The message
// names the file, the key, the value and what was expected (config/reader.hpp):
//   "sim.toml: bench.port = 70000: expected a TCP port 0..65535 (0: a free port)"
class SimRigConfigError : public config::ConfigError {
 public:
  using config::ConfigError::ConfigError;
};

struct SimRigConfig {
  std::string bench_config;  // path, resolved against the file's folder
  std::string bench_host = "127.0.0.1";
  int bench_port = 1502;
  std::string rig_geometry;  // path
  std::string target;        // path
  std::string calibration;   // path, or empty for vision::Camera::paper_default()
  CameraServerOptions camera;
  std::string realism_profile;  // path, or empty for the ideal world
  RealismProfile realism;       // read from realism_profile
};

// Reads the file (format above; a regular file of at most 1 MiB) and the
// realism profile it names. Throws SimRigConfigError, or RealismError for the
// profile. The other files it names are read by the bench and the camera.
SimRigConfig load_sim_rig_config(const std::string& path);

// `rig sim --realism NAME|FILE`: a NAME (letters, digits, '_', '-') is the
// file realism/NAME.toml beside the simulated rig file; anything else is a
// path. Reads the profile into config (realism, realism_profile and the
// camera's device version). Throws RealismError naming the file.
void override_realism(SimRigConfig* config, const std::string& sim_file,
                      const std::string& name_or_file);

// The hidden truth of the configured rig: the nominal calibration, rig
// geometry and target of the file, perturbed by its realism profile.
SimTruth sim_truth(const SimRigConfig& config);

// The camera of the configured rig: the renderer draws the truth's camera,
// lens and printed target with the profile's scene options, and maps bench
// positions through the truth's geometry, reading the bench's actual position
// through `position`. Not started.
std::unique_ptr<CameraServer> make_camera_server(const SimRigConfig& config,
                                                 BenchPositionFn position);

}  // namespace sim::camera
