#include "rig/sweep/run_record.hpp"

#include <aravis-0.8/arv.h>
#include <modbus/modbus-version.h>
#include <unistd.h>
#include <zmq.h>

#include <Eigen/Core>
#include <fstream>
#include <opencv2/core/version.hpp>
#include <sstream>

#include "config/json.hpp"
#include "db/store/sha256.hpp"

namespace rig::sweep {
namespace {

db::store::StoredFile stored_copy(const std::string& path, const std::string& key) {
  db::store::StoredFile file;
  file.path = path;
  if (path.empty()) return file;  // the built-in default; nothing to copy
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (!in) throw SweepConfigError(path + " (" + key + "): cannot be read to store it with the run");
  file.content = bytes.str();
  return file;
}

std::string host_name() {
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) != 0) return "unknown";
  return name;
}

}  // namespace

nlohmann::json library_versions() {
  int major = 0, minor = 0, patch = 0;
  zmq_version(&major, &minor, &patch);
  return {
      {"opencv", CV_VERSION},
      {"aravis", std::to_string(arv_get_major_version()) + "." +
                     std::to_string(arv_get_minor_version()) + "." +
                     std::to_string(arv_get_micro_version())},
      {"libmodbus", LIBMODBUS_VERSION_STRING},
      {"sqlite", db::store::sqlite_library_version()},
      {"zeromq", std::to_string(major) + "." + std::to_string(minor) + "." + std::to_string(patch)},
      {"eigen", std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) +
                    "." + std::to_string(EIGEN_MINOR_VERSION)}};
}

db::store::RunDescription describe_run(const SweepConfig& config, const SweepPlan& plan,
                                       const nlohmann::json& extra_config) {
  db::store::RunDescription d;
  nlohmann::json c = config.to_json();
  for (const auto& [key, value] : extra_config.items())
    c[key] = value;
  d.config_json = c.dump();
  d.plan_json = plan.to_json().dump();
  d.plan_size = static_cast<std::int64_t>(plan.size());
  d.sweep_file = stored_copy(config.sweep_file, "sweep file");
  d.camera_calibration = stored_copy(config.camera_calibration_path, "capture.calibration");
  d.target_layout = stored_copy(config.target_layout_path, "target.layout");
  d.bench_profile = stored_copy(config.bench_profile_path, "bench.profile");
  d.rig_geometry.path =
      config.rig_geometry_path.empty() ? config.sweep_file + " [rig]" : config.rig_geometry_path;
  d.rig_geometry.content = config.rig_geometry_text;
  d.software_version = RIG_VERSION;
  d.library_versions_json = library_versions().dump();
  d.host = host_name();
  d.primary_detector = config.detectors.front();  // registry order (sweep_config.hpp)
  return d;
}

nlohmann::json parse_stored_json(const std::string& text) {
  try {
    return config::parse_json(text, "stored JSON");
  } catch (const config::JsonInputError&) {
    return nlohmann::json(nlohmann::json::value_t::discarded);
  }
}

SweepPlan plan_for_resume(const db::store::Run& run, const SweepConfig& config,
                          bool completed_allowed) {
  const std::string which = "run " + std::to_string(run.id);
  if (run.status == db::store::RunStatus::kCompleted && !completed_allowed)
    throw RunMismatch(which + " is completed; there is nothing to resume");
  const nlohmann::json plan_json = parse_stored_json(run.description.plan_json);
  if (plan_json.is_discarded())
    throw PlanError(which + ": its stored plan is not valid JSON; the database is damaged");
  SweepPlan plan = SweepPlan::from_json(plan_json);
  const db::store::RunDescription now = describe_run(config, plan);
  const std::pair<const db::store::StoredFile*, const db::store::StoredFile*> files[] = {
      {&run.description.sweep_file, &now.sweep_file},
      {&run.description.camera_calibration, &now.camera_calibration},
      {&run.description.target_layout, &now.target_layout},
      {&run.description.bench_profile, &now.bench_profile},
      {&run.description.rig_geometry, &now.rig_geometry}};
  for (const auto& [stored, current] : files) {
    const std::string sha = db::store::sha256_hex(current->content);
    if (sha != stored->sha256)
      throw RunMismatch(which + ": " + current->path + " differs from the copy the run stored (" +
                        stored->path + ", SHA-256 " + stored->sha256.substr(0, 12) + "..., now " +
                        sha.substr(0, 12) + "...); a resumed run must measure with the files " +
                        "it started with");
  }
  return plan;
}

}  // namespace rig::sweep
