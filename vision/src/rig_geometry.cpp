#include "vision/rig_geometry.hpp"

#include <toml++/toml.h>

#include <Eigen/Geometry>
#include <cmath>

namespace vision {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Matrix3d rotation_from_vector_deg(const Eigen::Vector3d& r_deg) {
  const double angle = r_deg.norm() * kPi / 180.0;
  if (angle == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, r_deg.normalized()).toRotationMatrix();
}

// table[section][key] as three finite numbers.
Eigen::Vector3d read_vec3(const toml::table& table, const std::string& path,
                          const std::string& section, const std::string& key) {
  const std::string name = section + "." + key;
  const toml::node* node = table.at_path(name).node();
  if (node == nullptr)
    throw RigConfigError(path + ": missing key '" + name + "' (expected [x, y, z])");
  const toml::array* array = node->as_array();
  if (array == nullptr || array->size() != 3)
    throw RigConfigError(path + ": key '" + name + "' is not an array of three numbers");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    const auto value = (*array)[static_cast<size_t>(i)].value<double>();
    if (!value || !std::isfinite(*value))
      throw RigConfigError(path + ": key '" + name + "' element " + std::to_string(i) +
                           " is not a finite number");
    v[i] = *value;
  }
  return v;
}

}  // namespace

Eigen::Matrix3d RigGeometry::R_bench_nominal() {
  Eigen::Matrix3d R;
  // Columns: the camera's x, y, z axes in bench coordinates.
  R.col(0) = Eigen::Vector3d(0, -1, 0);
  R.col(1) = Eigen::Vector3d(0, 0, -1);
  R.col(2) = Eigen::Vector3d(1, 0, 0);
  return R;
}

RigGeometry RigGeometry::from_mount(const Eigen::Vector3d& mount_offset_mm,
                                    const Eigen::Vector3d& misalignment_deg,
                                    const Eigen::Vector3d& target_origin_mm,
                                    const Eigen::Vector3d& target_tilt_deg) {
  RigGeometry g;
  g.T_carriage_cam.R = R_bench_nominal() * rotation_from_vector_deg(misalignment_deg);
  g.T_carriage_cam.t = mount_offset_mm / 1000.0;
  g.T_bench_target.R = R_bench_nominal() * rotation_from_vector_deg(target_tilt_deg);
  g.T_bench_target.t = target_origin_mm / 1000.0;
  return g;
}

RigGeometry RigGeometry::load(const std::string& toml_path) {
  toml::table table;
  try {
    table = toml::parse_file(toml_path);
  } catch (const toml::parse_error& e) {
    throw RigConfigError(toml_path + ": cannot read the rig file: " + std::string(e.description()));
  }
  // Read in file order, so that the first missing key is the one reported.
  const Eigen::Vector3d offset = read_vec3(table, toml_path, "camera_mount", "offset_mm");
  const Eigen::Vector3d misalignment =
      read_vec3(table, toml_path, "camera_mount", "misalignment_deg");
  const Eigen::Vector3d origin = read_vec3(table, toml_path, "target", "origin_mm");
  const Eigen::Vector3d tilt = read_vec3(table, toml_path, "target", "tilt_deg");
  return from_mount(offset, misalignment, origin, tilt);
}

Pose RigGeometry::T_bench_carriage(double x_mm, double y_mm) {
  Pose T;
  T.t = Eigen::Vector3d(x_mm, y_mm, 0) / 1000.0;
  return T;
}

Pose RigGeometry::T_cam_target(double x_mm, double y_mm) const {
  return (T_bench_carriage(x_mm, y_mm) * T_carriage_cam).inverse() * T_bench_target;
}

}  // namespace vision
