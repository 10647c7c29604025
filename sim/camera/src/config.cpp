#include "sim/camera/config.hpp"

#include <toml++/toml.h>

#include <filesystem>
#include <stdexcept>

#include "vision/codebook.hpp"
#include "vision/target.hpp"

namespace sim::camera {
namespace {

class Reader {
 public:
  Reader(const std::string& path, const toml::table& table) : path_(path), table_(table) {
    folder_ = std::filesystem::path(path).parent_path();
  }
  template <typename T>
  T get(const std::string& key, T fallback) const {
    const toml::node* node = table_.at_path(key).node();
    if (node == nullptr) return fallback;
    const auto value = node->value<T>();
    if (!value) throw std::runtime_error(path_ + ": key '" + key + "' has the wrong type");
    return *value;
  }
  std::string required_path(const std::string& key) const {
    const std::string value = get<std::string>(key, "");
    if (value.empty())
      throw std::runtime_error(path_ + ": missing key '" + key + "' (a file path)");
    return resolve(value);
  }
  std::string resolve(const std::string& value) const {
    if (value.empty() || std::filesystem::path(value).is_absolute()) return value;
    return (folder_ / value).string();
  }

 private:
  std::string path_;
  const toml::table& table_;
  std::filesystem::path folder_;
};

}  // namespace

SimRigConfig load_sim_rig_config(const std::string& path) {
  toml::table table;
  try {
    table = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    throw std::runtime_error(path +
                             ": cannot read the sim rig file: " + std::string(e.description()));
  }
  const Reader r(path, table);
  SimRigConfig c;
  c.bench_config = r.required_path("bench.config");
  c.bench_host = r.get<std::string>("bench.host", c.bench_host);
  c.bench_port = static_cast<int>(r.get<int64_t>("bench.port", c.bench_port));
  if (c.bench_port < 0 || c.bench_port > 65535)
    throw std::runtime_error(path + ": key 'bench.port' = " + std::to_string(c.bench_port) +
                             " is not a TCP port (0..65535)");
  c.rig_geometry = r.required_path("camera.rig");
  c.target = r.required_path("camera.target");
  c.calibration = r.resolve(r.get<std::string>("camera.calibration", ""));
  CameraServerOptions& o = c.camera;
  o.interface_address = r.get<std::string>("camera.address", o.interface_address);
  o.serial = r.get<std::string>("camera.serial", o.serial);
  o.trigger_poll_hz = r.get<double>("camera.trigger_poll_hz", o.trigger_poll_hz);
  o.nominal_exposure_us = r.get<double>("camera.nominal_exposure_us", o.nominal_exposure_us);
  o.seed = static_cast<uint64_t>(r.get<int64_t>("camera.seed", static_cast<int64_t>(o.seed)));
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
