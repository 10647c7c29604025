#include "synthetic_pose.hpp"

namespace rig_test {

std::vector<Eigen::Vector3d> square_corners(double side_m, double cx, double cy) {
  const double h = side_m / 2;
  return {{cx - h, cy - h, 0}, {cx + h, cy - h, 0}, {cx + h, cy + h, 0}, {cx - h, cy + h, 0}};
}

Problem draw_problem(const vision::Camera& camera, const ProblemSpec& spec, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, spec.noise_px);
  Problem p;
  p.object_points = square_corners(spec.side_m);
  if (spec.whole_target) {
    // Three more markers beside the pose marker, 7 cm apart, as on the paper's sheet.
    for (const auto& c :
         {Eigen::Vector2d(0.07, 0), Eigen::Vector2d(0, 0.07), Eigen::Vector2d(0.07, 0.07)})
      for (const auto& q : square_corners(spec.side_m, c.x(), c.y()))
        p.object_points.push_back(q);
  }
  for (int attempt = 0; attempt < 100000; ++attempt) {
    const double distance =
        spec.min_distance_m + unit(rng) * (spec.max_distance_m - spec.min_distance_m);
    const Eigen::Vector2d pixel(unit(rng) * camera.width_px(), unit(rng) * camera.height_px());
    Eigen::Vector2d xy;
    if (!camera.undistort_point(pixel, &xy)) continue;
    const Eigen::Vector3d ray = xy.homogeneous().normalized();
    // Tilt: the sheet normal (target z) leans away from the line of sight by
    // `tilt` about a random axis perpendicular to it; then any in-plane turn.
    const double tilt = unit(rng) * spec.max_tilt_rad;
    const double axis_angle = unit(rng) * 2 * M_PI, spin = unit(rng) * 2 * M_PI;
    const Eigen::Vector3d z_target = ray;  // frontal: z into the sheet, along the ray
    const Eigen::Vector3d any =
        std::abs(z_target.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d u = z_target.cross(any).normalized(), v = z_target.cross(u);
    const Eigen::Vector3d tilt_axis = std::cos(axis_angle) * u + std::sin(axis_angle) * v;
    Eigen::Matrix3d frontal;
    frontal << u, v, z_target;
    const Eigen::Matrix3d R = Eigen::AngleAxisd(tilt, tilt_axis).toRotationMatrix() * frontal *
                              Eigen::AngleAxisd(spin, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    p.T_cam_target = {R, distance * ray};
    p.tilt_rad = tilt;
    p.image_points_px.clear();
    bool inside = true;
    for (const auto& P : p.object_points) {
      const Eigen::Vector3d q = p.T_cam_target * P;
      const Eigen::Vector2d px = camera.project(q);
      inside = inside && q.z() > 0 && px.x() >= spec.margin_px && px.y() >= spec.margin_px &&
               px.x() <= camera.width_px() - 1 - spec.margin_px &&
               px.y() <= camera.height_px() - 1 - spec.margin_px;
      p.image_points_px.push_back(px);
    }
    if (!inside) continue;
    if (spec.noise_px > 0)
      for (auto& px : p.image_points_px)
        px += Eigen::Vector2d(noise(rng), noise(rng));
    return p;
  }
  throw std::runtime_error("draw_problem: no visible pose found for the spec");
}

}  // namespace rig_test
