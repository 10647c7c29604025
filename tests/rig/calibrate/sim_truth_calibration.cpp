#include "sim_truth_calibration.hpp"

#include <Eigen/Geometry>

#include "sim/scene/renderer.hpp"
#include "synthetic_calibration.hpp"
#include "vision/codebook.hpp"
#include "vision/detector.hpp"

namespace rig_test {

vision::Camera sim_nominal_camera() {
  return vision::Camera::paper_default();
}

vision::RigGeometry sim_nominal_geometry(const std::string& source_dir) {
  return vision::RigGeometry::load(source_dir + "/config/rigs/sim.toml");
}

SimTruthSweep render_calibration_sweep(const SimTruthSweepSpec& spec) {
  sim::camera::RealismProfile profile = sim::camera::load_realism_profile(
      spec.source_dir + "/config/realism/" + spec.realism + ".toml");
  profile.truth.seed = spec.truth_seed;
  if (spec.bow_sag_mm) profile.scene.bow_sag_m = *spec.bow_sag_mm / 1000;
  if (spec.radial_k4) profile.scene.radial_k4 = *spec.radial_k4;
  const vision::Target layout = vision::Target::load(calibration_target_path(spec.source_dir));
  rig::calibrate::CalibrationProblem problem;
  problem.source = "simulated calibration sweep, truth seed " + std::to_string(spec.truth_seed);
  problem.nominal_camera = sim_nominal_camera();
  problem.nominal_geometry = sim_nominal_geometry(spec.source_dir);
  problem.target = layout;
  SimTruthSweep out{
      0, sim::camera::draw_truth(problem.nominal_camera, problem.nominal_geometry, layout, profile),
      std::move(problem)};
  out.truth_seed = spec.truth_seed;
  sim::scene::SceneOptions options = profile.scene;
  options.thin_prism = out.truth.thin_prism;
  const vision::Codebook codebook;
  const sim::scene::SceneRenderer renderer(out.truth.camera, out.truth.target, codebook, options);
  const vision::Detector detector(out.problem.nominal_camera, codebook);
  const std::vector<std::pair<double, double>> plan =
      read_csv_plan(calibration_plan_path(spec.source_dir));
  for (std::size_t i = 0; i < plan.size(); i += static_cast<std::size_t>(spec.position_stride)) {
    const auto [x_mm, y_mm] = plan[i];
    const vision::Pose T = out.truth.geometry.T_cam_target(x_mm, y_mm);
    for (int f = 0; f < spec.frames_per_position; ++f) {
      const std::uint64_t seed = spec.truth_seed * 1000003u + i * 16u + static_cast<unsigned>(f);
      const sim::scene::RenderedFrame frame = renderer.render(T, seed);
      ++out.frames;
      for (const sim::scene::MarkerTruth& m : frame.markers)
        out.markers_fully_visible += m.fully_visible ? 1 : 0;
      for (const vision::Detection& d : detector.detect(frame.image)) {
        if (!layout.has_marker(d.id)) continue;
        ++out.detections;
        const std::array<Eigen::Vector3d, 4> corners = layout.corners_m(d.id);
        for (int c = 0; c < 4; ++c)
          out.problem.corners.push_back({static_cast<std::int64_t>(i), x_mm, y_mm, d.id, c,
                                         corners[static_cast<std::size_t>(c)],
                                         d.corners_px[static_cast<std::size_t>(c)]});
      }
    }
  }
  return out;
}

Eigen::Vector3d camera_rotation_error_deg(const vision::RigGeometry& estimated,
                                          const vision::RigGeometry& truth) {
  const Eigen::AngleAxisd error(truth.T_carriage_cam.R.transpose() * estimated.T_carriage_cam.R);
  return error.axis() * error.angle() * 180.0 / 3.14159265358979323846;
}

}  // namespace rig_test
