#include "vision/rig_geometry.hpp"

#include <Eigen/Geometry>
#include <vector>

#include "config/reader.hpp"

namespace vision {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Matrix3d rotation_from_vector_deg(const Eigen::Vector3d& r_deg) {
  const double angle = r_deg.norm() * kPi / 180.0;
  if (angle == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, r_deg.normalized()).toRotationMatrix();
}

// A vector [x, y, z] of the file.
Eigen::Vector3d vec3(config::Table& table, const std::string& key) {
  const std::vector<double> v = table.numbers(key, 3, 3, "[x, y, z], three finite numbers");
  return Eigen::Vector3d(v[0], v[1], v[2]);
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

RigGeometry RigGeometry::read(config::Table& table) {
  config::Table mount = table.table("camera_mount");
  const Eigen::Vector3d offset = vec3(mount, "offset_mm");
  const Eigen::Vector3d misalignment = vec3(mount, "misalignment_deg");
  mount.reject_unknown();
  config::Table target = table.table("target");
  const Eigen::Vector3d origin = vec3(target, "origin_mm");
  const Eigen::Vector3d tilt = vec3(target, "tilt_deg");
  target.reject_unknown();
  return from_mount(offset, misalignment, origin, tilt);
}

RigGeometry RigGeometry::load(const config::Document& rig_file) {
  config::Table root = rig_file.root();
  const RigGeometry geometry = read(root);
  root.reject_unknown();
  return geometry;
}

RigGeometry RigGeometry::load(const std::string& toml_path) {
  return load(config::Document::read<RigConfigError>(toml_path, "the rig file"));
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
