// vision::RigGeometry: where the camera and the target are on the bench, so
// that a bench position (x_mm, y_mm) gives the true pose T_cam_target.
//
// Frames (right-handed; metres in this API, millimetres and degrees in the file):
//   bench    origin at the carriage reference point when the bench reads
//            (0, 0); x along the bench X axis, y along the bench Y axis, z up.
//   carriage the bench frame translated to the carriage at (x_mm, y_mm):
//            T_bench_carriage = translation (x_mm, y_mm, 0) / 1000.
//   camera   x right, y down, z forward (vision/camera.hpp). Nominally mounted
//            looking along bench +x, upright: x_cam = -y_bench, y_cam = -z_bench,
//            z_cam = +x_bench; then moved by the mount offset and turned by the
//            mount misalignment.
//   target   x right on the sheet, y down, z into the sheet (vision/target.hpp).
//            Nominally facing the camera: the same axes as the nominal camera;
//            then tilted.
// So   T_cam_target(x, y) = (T_bench_carriage(x, y) * T_carriage_cam)^-1 * T_bench_target.
//
// File (TOML), e.g. config/rigs/sim.toml:
//   [camera_mount]
//   offset_mm = [0.0, 0.0, 0.0]        # optical centre from the carriage reference, bench axes
//   misalignment_deg = [0.3, -0.2, 0.5]  # rotation vector about the nominal camera axes
//   [target]
//   origin_mm = [600.0, 150.0, 0.0]    # target-frame origin, bench frame
//   tilt_deg = [1.0, -2.0, 0.0]        # rotation vector about the nominal target axes
// A rotation vector (rx, ry, rz) turns by |r| degrees about the axis r / |r|;
// for the small angles of a mount error it is rx about x, ry about y, rz about z.
// Every key is required; a key or table not listed is refused.
#pragma once

#include <Eigen/Core>
#include <string>

#include "config/error.hpp"
#include "vision/pose.hpp"

namespace config {
class Document;
class Table;
}  // namespace config

namespace vision {

// A rig file that cannot be read, lacks a key, holds an unknown key or a
// malformed value. The message names the file, the key, the value and what
// was expected (config/reader.hpp), e.g.
//   "sim.toml: target.origin_mm = [600, \"far\", 0]: expected [x, y, z], three finite numbers"
// A config::ConfigError: bad input.
class RigConfigError : public config::ConfigError {
 public:
  using config::ConfigError::ConfigError;
};

struct RigGeometry {
  Pose T_carriage_cam;  // camera in the carriage frame, metres
  Pose T_bench_target;  // target in the bench frame, metres

  // The nominal camera orientation in bench axes (looking along +x, upright),
  // also the nominal target orientation.
  static Eigen::Matrix3d R_bench_nominal();

  // Builds the geometry from the file's quantities (mm, degrees).
  static RigGeometry from_mount(const Eigen::Vector3d& mount_offset_mm,
                                const Eigen::Vector3d& misalignment_deg,
                                const Eigen::Vector3d& target_origin_mm,
                                const Eigen::Vector3d& target_tilt_deg);

  // Reads a rig file (format above; a regular file of at most 1 MiB). Throws
  // RigConfigError.
  static RigGeometry load(const std::string& toml_path);
  // The same from a parsed rig file (a caller that also keeps its text).
  // Errors are the Document's (RigConfigError when read as a rig file).
  static RigGeometry load(const config::Document& rig_file);
  // Reads the tables [camera_mount] and [target] of `table` (a rig file's
  // root, or the [rig] table of a sweep file that gives the geometry inline),
  // refusing unknown keys inside them; the other keys of `table` are the
  // caller's. Errors are the Table's, naming its file and the dotted key.
  static RigGeometry read(config::Table& table);

  static Pose T_bench_carriage(double x_mm, double y_mm);
  // The true pose of the target in the camera frame with the carriage at (x_mm, y_mm).
  Pose T_cam_target(double x_mm, double y_mm) const;
  // Distance from the camera's optical centre to the target-frame origin, metres.
  double distance_m(double x_mm, double y_mm) const {
    return T_cam_target(x_mm, y_mm).distance_m();
  }
};

}  // namespace vision
