#include "sim/camera/config.hpp"

#include <cstdint>
#include <filesystem>

#include "config/reader.hpp"
#include "vision/marker_family.hpp"
#include "vision/target.hpp"

namespace sim::camera {
namespace {

void read_bench(config::Table bench, SimRigConfig* c) {
  c->bench_config = bench.existing_file("config", "a bench file (drive profile and [sim] table)");
  c->bench_host = bench.string_or("host", c->bench_host, "a listening address, e.g. \"127.0.0.1\"");
  c->bench_port = static_cast<int>(
      bench.integer_or("port", c->bench_port, 0, 65535, "a TCP port 0..65535 (0: a free port)"));
  bench.reject_unknown();
}

void read_camera(config::Table camera, SimRigConfig* c) {
  c->rig_geometry = camera.existing_file("rig", "a rig file (vision/rig_geometry.hpp)");
  c->target = camera.existing_file("target", "a target layout (vision/target.hpp)");
  const std::string calibration = camera.string_or(
      "calibration", "", "a camera calibration file, or \"\" for the paper's Sony XC-555");
  if (!calibration.empty()) {
    c->calibration = camera.existing_file("calibration", "a camera calibration file");
  }
  CameraServerOptions& o = c->camera;
  o.interface_address =
      camera.string_or("address", o.interface_address, "a GigE Vision interface address");
  o.serial = camera.string_or("serial", o.serial, "a serial number, e.g. \"RIGSIM01\"");
  o.trigger_poll_hz = camera.number_or("trigger_poll_hz", o.trigger_poll_hz, config::positive());
  o.nominal_exposure_us =
      camera.number_or("nominal_exposure_us", o.nominal_exposure_us, config::positive());
  o.seed = static_cast<std::uint64_t>(
      camera.integer_or("seed", static_cast<std::int64_t>(o.seed), 0, INT64_MAX));
  o.genicam = camera.choice_or("genicam", o.genicam, {"sfnc", "legacy"});
  camera.reject_unknown();
}

void use_profile(SimRigConfig* c, const std::string& path) {
  c->realism_profile = path;
  c->realism = load_realism_profile(path);
  c->camera.device_version = "realism " + c->realism.name;
}

}  // namespace

SimRigConfig load_sim_rig_config(const std::string& path) {
  const config::Document file =
      config::Document::read<SimRigConfigError>(path, "the simulated rig file");
  config::Table root = file.root();
  SimRigConfig c;
  read_bench(root.table("bench"), &c);
  read_camera(root.table("camera"), &c);
  config::Table realism = root.optional_table("realism");
  const std::string profile =
      realism.exists() ? realism.existing_file("profile", "a realism profile (config/realism/)")
                       : std::string();
  realism.reject_unknown();
  root.reject_unknown();
  if (!profile.empty()) use_profile(&c, profile);
  return c;
}

void override_realism(SimRigConfig* config, const std::string& sim_file,
                      const std::string& name_or_file) {
  const bool is_name =
      !name_or_file.empty() &&
      name_or_file.find_first_not_of(
          "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") == std::string::npos;
  const std::string path =
      is_name
          ? (std::filesystem::path(sim_file).parent_path() / "realism" / (name_or_file + ".toml"))
                .string()
          : name_or_file;
  use_profile(config, path);
}

SimTruth sim_truth(const SimRigConfig& config) {
  const vision::Camera camera = config.calibration.empty()
                                    ? vision::Camera::paper_default()
                                    : vision::Camera::load(config.calibration);
  return draw_truth(camera, vision::RigGeometry::load(config.rig_geometry),
                    vision::Target::load(config.target), config.realism);
}

std::unique_ptr<CameraServer> make_camera_server(const SimRigConfig& config,
                                                 BenchPositionFn position) {
  SimTruth truth = sim_truth(config);
  scene::SceneOptions options = config.realism.scene;
  options.thin_prism = truth.thin_prism;
  options.exposure_time_s = config.camera.nominal_exposure_us * 1e-6;
  // The sheet in the target's own family (rig4x4 unless the layout names another).
  auto renderer = std::make_shared<const scene::SceneRenderer>(
      truth.camera, truth.target, vision::MarkerFamily::named(truth.target.family), options);
  CameraServerOptions server_options = config.camera;
  server_options.bayer_rg = config.realism.bayer_rg;
  server_options.filter_response = config.realism.filter_response;
  auto camera = std::make_unique<CameraServer>(std::move(renderer), truth.geometry,
                                               std::move(position), server_options);
  if (!config.realism.attitude.zero()) {
    camera->set_pose_model(
        [attitude = config.realism.attitude, geometry = truth.geometry](double x_mm, double y_mm) {
          return attitude.T_cam_target(geometry, x_mm, y_mm);
        });
  }
  return camera;
}

}  // namespace sim::camera
