#include "sim_truth_calibration.hpp"

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>

#include "db/store/sha256.hpp"
#include "db/store/store.hpp"
#include "sim/scene/renderer.hpp"
#include "synthetic_calibration.hpp"
#include "vision/codebook.hpp"
#include "vision/detector.hpp"
#include "vision/image_codecs.hpp"

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
      spec.truth_seed,
      sim::camera::draw_truth(problem.nominal_camera, problem.nominal_geometry, layout, profile),
      0,
      std::move(problem),
      {},
      0,
      0,
      0};
  sim::scene::SceneOptions options = profile.scene;
  options.thin_prism = out.truth.thin_prism;
  out.radial_k4 = options.radial_k4;
  const vision::Codebook codebook;
  const sim::scene::SceneRenderer renderer(out.truth.camera, out.truth.target, codebook, options);
  const std::unique_ptr<vision::FiducialDetector> detector =
      vision::make_detector(out.problem.detector, out.problem.nominal_camera, layout.family);
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
      const rig::calibrate::CalibrationFrame where{static_cast<std::int64_t>(i), x_mm, y_mm, "",
                                                   ""};
      const std::vector<rig::calibrate::CornerObservation> corners =
          rig::calibrate::detect_corners(*detector, layout, where, frame.image);
      out.detections += corners.size() / 4;
      out.problem.corners.insert(out.problem.corners.end(), corners.begin(), corners.end());
      out.problem.frames.push_back(where);
      out.images.push_back(frame.image);
    }
  }
  return out;
}

rig::calibrate::CalibrationProblem redetected(const SimTruthSweep& sweep,
                                              const vision::Camera& camera) {
  const std::unique_ptr<vision::FiducialDetector> detector =
      vision::make_detector(sweep.problem.detector, camera, sweep.problem.target.family);
  rig::calibrate::CalibrationProblem out = sweep.problem;
  out.corners.clear();
  for (std::size_t i = 0; i < sweep.images.size(); ++i) {
    const std::vector<rig::calibrate::CornerObservation> corners = rig::calibrate::detect_corners(
        *detector, sweep.problem.target, sweep.problem.frames[i], sweep.images[i]);
    out.corners.insert(out.corners.end(), corners.begin(), corners.end());
  }
  return out;
}

std::int64_t write_sim_truth_run(const SimTruthSweep& sweep, const std::string& source_dir,
                                 const std::string& db_path, const std::string& frames_dir) {
  db::store::StoreOptions options;
  options.durable_commits = false;
  db::store::Store store(db_path, options);
  const std::string rig = source_dir + "/config/rigs/sim.toml";
  std::map<std::int64_t, db::store::PositionRecord> positions;
  for (std::size_t i = 0; i < sweep.images.size(); ++i) {
    const rig::calibrate::CalibrationFrame& where = sweep.problem.frames[i];
    db::store::PositionRecord& p = positions[where.plan_index];
    p.plan_index = where.plan_index;
    p.commanded_x_mm = where.x_mm;
    p.commanded_y_mm = where.y_mm;
    p.measured_x_mm = where.x_mm;
    p.measured_y_mm = where.y_mm;
    db::store::FrameRecord frame;
    frame.index = static_cast<int>(p.frames.size());
    frame.source = "sim_truth_calibration";
    const std::string path = frames_dir + "/p" + std::to_string(where.plan_index) + "_f" +
                             std::to_string(frame.index) + ".png";
    std::vector<std::uint8_t> png;
    vision::imencode(".png", sweep.images[i], png);
    const std::string bytes(png.begin(), png.end());
    std::ofstream(path, std::ios::binary) << bytes;
    frame.image_path = path;
    frame.image_sha256 = db::store::sha256_hex(bytes);
    p.frames.push_back(frame);
  }
  // The stored detections, one frame per position (the first): each marker's
  // corners A..D from the observations.
  for (const rig::calibrate::CornerObservation& c : sweep.problem.corners) {
    std::vector<db::store::DetectionRecord>& found =
        positions[c.plan_index].frames.front().detections;
    auto it = std::find_if(found.begin(), found.end(), [&](const db::store::DetectionRecord& r) {
      return r.marker_id == c.marker_id;
    });
    if (it == found.end()) {
      db::store::DetectionRecord det;
      det.detector = sweep.problem.detector;
      det.marker_id = c.marker_id;
      det.corners_px.fill(std::nan(""));
      it = found.insert(found.end(), det);
    }
    it->corners_px[2 * static_cast<std::size_t>(c.corner)] = c.pixel.x();
    it->corners_px[2 * static_cast<std::size_t>(c.corner) + 1] = c.pixel.y();
  }
  db::store::RunDescription d = calibration_run_description(
      sweep.problem.nominal_camera, calibration_target_path(source_dir), rig, read_file(rig),
      positions.empty() ? 0 : positions.rbegin()->first + 1);
  d.primary_detector = sweep.problem.detector;
  const std::int64_t run = store.start_run(d);
  for (const auto& [index, p] : positions)
    store.append_position(run, p);
  store.finish_run(run, db::store::RunStatus::kCompleted, "");
  return run;
}

namespace {

// The simulated lens's projection of an undistorted normalised point: the
// camera's model plus the thin prism and the r^8 term, as sim::scene renders
// (sim/scene/src/lens.hpp).
Eigen::Vector2d true_pixel(const SimTruthSweep& sweep, const Eigen::Vector2d& xy) {
  const vision::Camera& c = sweep.truth.camera;
  const std::array<double, 4>& s = sweep.truth.thin_prism;
  const double r2 = xy.squaredNorm(), r8 = r2 * r2 * r2 * r2;
  Eigen::Vector2d px = c.distort_normalized(xy);
  px.x() += c.intrinsics().fx * (s[0] * r2 + s[1] * r2 * r2 + xy.x() * sweep.radial_k4 * r8);
  px.y() += c.intrinsics().fy * (s[2] * r2 + s[3] * r2 * r2 + xy.y() * sweep.radial_k4 * r8);
  return px;
}

// The 5-coefficient camera and frame rotation of parameters p = (fx, fy,
// cx, cy, k1, k2, p1, p2, k3, rotation vector in radians).
using GaugeParameters = Eigen::Matrix<double, 12, 1>;

vision::Camera model_camera(const GaugeParameters& p, const vision::Camera& like) {
  return vision::Camera({p(0), p(1), p(2), p(3)}, {p(4), p(5), p(6), p(7), p(8)}, like.width_px(),
                        like.height_px());
}

Eigen::VectorXd gauge_residuals(const GaugeParameters& p, const vision::Camera& like,
                                const std::vector<Eigen::Vector2d>& rays,
                                const std::vector<Eigen::Vector2d>& true_px) {
  const vision::Camera camera = model_camera(p, like);
  const Eigen::Vector3d w = p.tail<3>();
  const Eigen::Matrix3d R = w.norm() > 0 ? Eigen::AngleAxisd(w.norm(), w.normalized()).matrix()
                                         : Eigen::Matrix3d::Identity();
  Eigen::VectorXd r(2 * rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i)
    r.segment<2>(2 * static_cast<Eigen::Index>(i)) =
        camera.project(R * rays[i].homogeneous()) - true_px[i];
  return r;
}

}  // namespace

LensInModel lens_in_five_coefficients(const SimTruthSweep& sweep) {
  const vision::Camera& truth = sweep.truth.camera;
  // Image points on a grid inside the image's border, taken back to rays
  // through the true camera's Brown-Conrady part (the prism and r^8 terms,
  // below 0.2 px, only move where a ray lands, not which rays are used).
  std::vector<Eigen::Vector2d> rays, true_px;
  for (int j = 0; j < 36; ++j)
    for (int i = 0; i < 48; ++i) {
      const Eigen::Vector2d px((i + 0.5) * truth.width_px() / 48.0,
                               (j + 0.5) * truth.height_px() / 36.0);
      Eigen::Vector2d xy;
      if (!truth.undistort_point(px, &xy)) continue;
      rays.push_back(xy);
      true_px.push_back(true_pixel(sweep, xy));
    }
  // Gauss-Newton from the true camera and no rotation, central differences
  // (the problem is nearly linear: on the lab seeds the third step already
  // moved the rotation by less than 1e-12 rad, measured; five are taken).
  GaugeParameters p;
  const vision::Intrinsics& k = truth.intrinsics();
  const vision::Distortion& d = truth.distortion();
  p << k.fx, k.fy, k.cx, k.cy, d.k1, d.k2, d.p1, d.p2, d.k3, 0, 0, 0;
  const GaugeParameters step_of =
      (GaugeParameters() << 1e-3, 1e-3, 1e-3, 1e-3, 1e-7, 1e-7, 1e-8, 1e-8, 1e-7, 1e-8, 1e-8, 1e-8)
          .finished();
  for (int iteration = 0; iteration < 5; ++iteration) {
    const Eigen::VectorXd r = gauge_residuals(p, truth, rays, true_px);
    Eigen::MatrixXd J(r.size(), 12);
    for (int c = 0; c < 12; ++c) {
      GaugeParameters plus = p, minus = p;
      plus(c) += step_of(c);
      minus(c) -= step_of(c);
      J.col(c) = (gauge_residuals(plus, truth, rays, true_px) -
                  gauge_residuals(minus, truth, rays, true_px)) /
                 (2 * step_of(c));
    }
    p -= J.colPivHouseholderQr().solve(r);
  }
  const Eigen::VectorXd r = gauge_residuals(p, truth, rays, true_px);
  return {model_camera(p, truth), p.tail<3>() * 180.0 / 3.14159265358979323846,
          std::sqrt(r.squaredNorm() / static_cast<double>(rays.size()))};
}

vision::RigGeometry geometry_in_model(const vision::RigGeometry& truth, const LensInModel& lens) {
  const Eigen::Vector3d w = lens.rotation_deg * 3.14159265358979323846 / 180.0;
  vision::RigGeometry g = truth;
  if (w.norm() > 0)
    g.T_carriage_cam.R =
        truth.T_carriage_cam.R * Eigen::AngleAxisd(w.norm(), w.normalized()).matrix().transpose();
  return g;
}

Eigen::Vector3d camera_rotation_error_deg(const vision::RigGeometry& estimated,
                                          const vision::RigGeometry& truth) {
  const Eigen::AngleAxisd error(truth.T_carriage_cam.R.transpose() * estimated.T_carriage_cam.R);
  return error.axis() * error.angle() * 180.0 / 3.14159265358979323846;
}

}  // namespace rig_test
