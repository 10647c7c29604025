#include "sim/camera/config.hpp"

#include <cstdint>

#include "config/reader.hpp"
#include "vision/codebook.hpp"
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
  camera.reject_unknown();
}

}  // namespace

SimRigConfig load_sim_rig_config(const std::string& path) {
  const config::Document file =
      config::Document::read<SimRigConfigError>(path, "the simulated rig file");
  config::Table root = file.root();
  SimRigConfig c;
  read_bench(root.table("bench"), &c);
  read_camera(root.table("camera"), &c);
  root.reject_unknown();
  return c;
}

std::unique_ptr<CameraServer> make_camera_server(const SimRigConfig& config,
                                                 BenchPositionFn position) {
  const vision::Camera camera = config.calibration.empty()
                                    ? vision::Camera::paper_default()
                                    : vision::Camera::load(config.calibration);
  auto renderer = std::make_shared<const scene::SceneRenderer>(
      camera, vision::Target::load(config.target), vision::Codebook());
  return std::make_unique<CameraServer>(std::move(renderer),
                                        vision::RigGeometry::load(config.rig_geometry),
                                        std::move(position), config.camera);
}

}  // namespace sim::camera
