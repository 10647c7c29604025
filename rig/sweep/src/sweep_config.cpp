// Reading and validating sweep files (see sweep_config.hpp).
#include "rig/sweep/sweep_config.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

#include "motion/bench_url.hpp"
#include "motion/errors.hpp"
#include "rig/sweep/pose_json.hpp"
#include "rig/telemetry/telemetry.hpp"
#include "sweep_file_section.hpp"

namespace rig::sweep {
namespace {

namespace fs = std::filesystem;
using sweep_file::existing_file;
using sweep_file::load_named;
using sweep_file::num;
using sweep_file::repr;
using sweep_file::resolve;
using sweep_file::Section;

constexpr const char* kCameraForms =
    "a camera spec gige:ADDRESS | gige:ID | v4l2:PATH | replay:DIR";
constexpr const char* kBenchForms =
    "a bench URL modbus-tcp://HOST:PORT or modbus-rtu:///dev/DEVICE?baud=...";

SweepPlan read_plan(Section& s, const fs::path& base_dir, const motion::SoftLimits& limits) {
  const std::string kind = s.string("kind", "\"grid\", \"csv\" or \"paper\"");
  // The keys that belong to each kind; any other kind's key is an error.
  const std::vector<std::pair<std::string, std::set<std::string>>> kinds = {
      {"grid", {"x_mm", "y_mm", "serpentine"}}, {"csv", {"file"}}, {"paper", {"x_mm", "y_mm"}}};
  const auto own =
      std::find_if(kinds.begin(), kinds.end(), [&](const auto& k) { return k.first == kind; });
  if (own == kinds.end()) s.fail("kind", s.take("kind"), "\"grid\", \"csv\" or \"paper\"");
  for (const auto& [other, keys] : kinds) {
    for (const std::string& key : keys) {
      if (!own->second.count(key) && s.has(key)) {
        s.fail(key, s.take(key), "exactly one kind of plan",
               "plan." + key + " belongs to kind = \"" + other + "\", not \"" + kind + "\"");
      }
    }
  }

  SweepPlan plan;
  if (kind == "grid") {
    const std::string expected = "[min, max, step] in mm with min <= max and step > 0";
    const std::vector<double> x = s.numbers("x_mm", 3, 3, expected);
    if (x[1] < x[0] || x[2] <= 0) s.fail("x_mm", s.take("x_mm"), expected);
    const std::vector<double> y = s.numbers("y_mm", 3, 3, expected);
    if (y[1] < y[0] || y[2] <= 0) s.fail("y_mm", s.take("y_mm"), expected);
    const bool serpentine = s.boolean_or("serpentine", true);
    plan = load_named(
        s, "x_mm", "a grid of at most " + std::to_string(SweepPlan::kMaxPositions) + " positions",
        [&] {
          return SweepPlan::grid({x[0], x[1], x[2], y[0], y[1], y[2], serpentine});
        });
  } else if (kind == "csv") {
    const std::string path = existing_file(s, base_dir, "file", "a CSV plan (x_mm,y_mm)");
    plan = load_named(s, "file", "a CSV plan", [&] { return SweepPlan::from_csv(path); });
  } else {
    const std::string expected = "[min, max] in mm with min < max";
    std::vector<double> x = {limits.x_min_mm, limits.x_max_mm};
    std::vector<double> y = {limits.y_min_mm, limits.y_max_mm};
    if (s.has("x_mm")) x = s.numbers("x_mm", 2, 2, expected);
    if (!(x[0] < x[1])) s.fail("x_mm", s.take("x_mm"), expected);
    if (s.has("y_mm")) y = s.numbers("y_mm", 2, 2, expected);
    if (!(y[0] < y[1])) s.fail("y_mm", s.take("y_mm"), expected);
    plan = SweepPlan::paper(x[0], x[1], y[0], y[1]);
  }
  s.reject_unknown("kind, x_mm, y_mm, serpentine, file");

  // Every position inside the soft limits, before anything moves.
  for (std::size_t i = 0; i < plan.size(); ++i) {
    const PlanPosition& p = plan.positions()[i];
    if (!limits.contains(p.x_mm, p.y_mm)) {
      const bool x_inside = p.x_mm >= limits.x_min_mm && p.x_mm <= limits.x_max_mm;
      const std::string key = kind == "csv" ? "file" : x_inside ? "y_mm" : "x_mm";
      s.fail(key, s.take(key),
             "every position inside the bench's soft limits x " + num(limits.x_min_mm) + ".." +
                 num(limits.x_max_mm) + " mm, y " + num(limits.y_min_mm) + ".." +
                 num(limits.y_max_mm) + " mm",
             "position " + std::to_string(i) + " (x " + num(p.x_mm) + ", y " + num(p.y_mm) +
                 " mm) is outside");
    }
  }
  return plan;
}

void check_camera_spec(Section& s, const fs::path& base_dir, std::string* spec) {
  const auto colon = spec->find(':');
  const std::string scheme = colon == std::string::npos ? "" : spec->substr(0, colon);
  const std::string rest = colon == std::string::npos ? "" : spec->substr(colon + 1);
  if ((scheme != "gige" && scheme != "v4l2" && scheme != "replay") || rest.empty()) {
    s.fail("camera", s.take("camera"), kCameraForms);
  }
  if (scheme == "replay") {
    // Recorded frames are data next to the sweep file: resolve and require them now.
    const std::string dir = resolve(base_dir, rest);
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) {
      s.fail("camera", s.take("camera"), "replay:DIR with an existing folder",
             dir + " is not a folder");
    }
    *spec = "replay:" + dir;
  }
}

// A ZeroMQ endpoint the telemetry may bind: tcp://HOST:PORT or ipc://PATH;
// without allow_remote a TCP host must be loopback.
// The endpoint checked by the rules the telemetry itself binds by
// (rig/telemetry.hpp), reported as a sweep file error.
void check_endpoint(Section& s, const std::string& key, const std::string& endpoint,
                    bool allow_remote) {
  try {
    telemetry::validate_endpoint(endpoint, allow_remote, "endpoint");
  } catch (const telemetry::EndpointError& e) {
    s.fail(key, s.take(key),
           "an endpoint tcp://HOST:PORT, ipc://PATH or inproc://NAME on this machine unless "
           "telemetry.allow_remote = true",
           e.what());
  }
}

// The geometry from a rig file or from inline [rig.camera_mount] / [rig.target].
void read_rig(Section& s, const fs::path& base_dir, SweepConfig* c) {
  const bool inline_tables = s.has("camera_mount") || s.has("target");
  const std::string one_of =
      "exactly one of rig.file = \"RIG.toml\" or the tables [rig.camera_mount] and [rig.target]";
  if (!s.has("file") && !inline_tables) s.fail("file", nullptr, one_of);
  if (s.has("file") && inline_tables) {
    s.fail("file", s.take("file"), one_of, "inline rig tables are given too");
  }
  if (s.has("file")) {
    c->rig_geometry_path = existing_file(s, base_dir, "file", "a rig file (vision/rig_geometry)");
    c->geometry = load_named(s, "file", "a rig file",
                             [&] { return vision::RigGeometry::load(c->rig_geometry_path); });
    std::ifstream in(c->rig_geometry_path);
    std::ostringstream text;
    text << in.rdbuf();
    c->rig_geometry_text = text.str();
  } else {
    const std::string expected = "[x, y, z], three finite numbers";
    auto vec3 = [&](Section& t, const std::string& key) {
      const std::vector<double> v = t.numbers(key, 3, 3, expected);
      return Eigen::Vector3d(v[0], v[1], v[2]);
    };
    Section mount(s.file(), s.field("camera_mount"), s.table("camera_mount"));
    Section target(s.file(), s.field("target"), s.table("target"));
    if (!s.has("camera_mount")) s.fail("camera_mount", nullptr, "a table [rig.camera_mount]");
    if (!s.has("target")) s.fail("target", nullptr, "a table [rig.target]");
    const Eigen::Vector3d offset = vec3(mount, "offset_mm");
    const Eigen::Vector3d misalignment = vec3(mount, "misalignment_deg");
    mount.reject_unknown("offset_mm, misalignment_deg");
    const Eigen::Vector3d origin = vec3(target, "origin_mm");
    const Eigen::Vector3d tilt = vec3(target, "tilt_deg");
    target.reject_unknown("origin_mm, tilt_deg");
    c->geometry = vision::RigGeometry::from_mount(offset, misalignment, origin, tilt);
    toml::table geometry;
    geometry.insert("camera_mount", *s.table("camera_mount"));
    geometry.insert("target", *s.table("target"));
    std::ostringstream text;
    text << geometry;
    c->rig_geometry_text = text.str() + "\n";
  }
  s.reject_unknown("file, camera_mount, target");
}

template <typename T>
nlohmann::json optional_json(const std::optional<T>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

}  // namespace

nlohmann::json SweepConfig::to_json() const {
  using nlohmann::json;
  const vision::Intrinsics& k = camera.intrinsics();
  const vision::Distortion& d = camera.distortion();
  json markers = json::array();
  for (const vision::TargetMarker& m : target.markers) {
    markers.push_back(
        {{"id", m.id}, {"side_m", m.side_m}, {"centre_m", {m.centre_m.x(), m.centre_m.y()}}});
  }
  const motion::SoftLimits& limits = bench_profile.soft_limits;
  return {
      {"sweep_file", sweep_file},
      {"plan", {{"description", plan.description()}, {"size", plan.size()}}},
      {"capture",
       {{"camera", camera_spec},
        {"calibration", camera_calibration_path},
        {"frames_per_position", frames_per_position},
        {"software_trigger", capture.software_trigger},
        {"pixel_format", capture.pixel_format},
        {"exposure_us", optional_json(capture.exposure_us)},
        {"gain", optional_json(capture.gain)},
        {"grab_timeout_ms", faults.grab_timeout.count()},
        {"retries", faults.capture_retries},
        {"save_frames", optional_json(frames_dir)}}},
      {"camera",
       {{"width_px", camera.width_px()},
        {"height_px", camera.height_px()},
        {"fx", k.fx},
        {"fy", k.fy},
        {"cx", k.cx},
        {"cy", k.cy},
        {"k1", d.k1},
        {"k2", d.k2},
        {"p1", d.p1},
        {"p2", d.p2},
        {"k3", d.k3}}},
      {"bench",
       {{"url", bench_url},
        {"profile", bench_profile_path},
        {"profile_name", bench_profile.name},
        {"speed_mm_s", speed_mm_s.value_or(bench_profile.default_speed_mm_s)},
        {"speed_from_profile", !speed_mm_s.has_value()},
        {"max_speed_mm_s", bench_profile.max_speed_mm_s},
        {"home_first", home_first},
        {"soft_limits_mm",
         {{"x", {limits.x_min_mm, limits.x_max_mm}}, {"y", {limits.y_min_mm, limits.y_max_mm}}}}}},
      {"settle", {{"timeout_ms", settle.timeout.count()}, {"dwell_ms", settle.dwell.count()}}},
      {"faults",
       {{"on_alarm", faults.on_alarm == AlarmAction::kPause ? "pause" : "abort"},
        {"max_consecutive_failed", faults.max_consecutive_failed_positions},
        {"link_retries", faults.link_retries}}},
      {"target",
       {{"layout", target_layout_path},
        {"name", target.name},
        {"pose_marker", target.pose_marker_id},
        {"markers", markers}}},
      {"rig",
       {{"file", rig_geometry_path},
        {"toml", rig_geometry_text},
        {"T_carriage_cam", pose_to_json(geometry.T_carriage_cam, "t_m")},
        {"T_bench_target", pose_to_json(geometry.T_bench_target, "t_m")}}},
      {"database", {{"path", database_path}, {"durable_commits", durable_commits}}},
      {"telemetry",
       {{"publish", telemetry_publish},
        {"control", telemetry_control},
        {"allow_remote", telemetry_allow_remote}}},
  };
}

SweepConfig load_sweep_config(const std::string& path) {
  SweepConfig c;
  c.sweep_file = fs::absolute(path).lexically_normal().string();
  const fs::path base_dir = fs::path(c.sweep_file).parent_path();
  {
    std::ifstream in(c.sweep_file, std::ios::binary);
    if (!in) throw SweepConfigError(c.sweep_file + ": cannot open the sweep file");
    std::ostringstream text;
    text << in.rdbuf();
    c.sweep_file_text = text.str();
  }
  toml::table root;
  try {
    root = toml::parse(c.sweep_file_text, c.sweep_file);
  } catch (const toml::parse_error& e) {
    throw SweepConfigError(c.sweep_file + ": line " + std::to_string(e.source().begin.line) + ": " +
                           std::string(e.description()) + ": expected valid TOML");
  }
  const std::string& file = c.sweep_file;
  Section top(file, "", &root);
  // Unknown tables first: a misspelt [setle] must not let its defaults be checked.
  for (const char* name :
       {"plan", "capture", "bench", "settle", "faults", "target", "rig", "database", "telemetry"}) {
    top.take(name);
  }
  top.reject_unknown(
      "the tables [plan], [capture], [bench], [settle], [faults], [target], [rig], [database], "
      "[telemetry]");
  auto section = [&](const std::string& name, bool required) {
    const toml::table* t = top.table(name);
    if (t == nullptr && required) top.fail(name, nullptr, "a table [" + name + "]");
    return Section(file, name, t);
  };

  // [bench] first: the plan is checked against its profile.
  Section bench = section("bench", true);
  c.bench_url = bench.string("url", kBenchForms);
  load_named(bench, "url", "a valid bench URL",
             [&] { return motion::BenchUrl::parse(c.bench_url); });
  c.bench_profile_path = existing_file(bench, base_dir, "profile", "a drive profile");
  c.bench_profile = load_named(bench, "profile", "a drive profile (motion/drive_profile)",
                               [&] { return motion::load_drive_profile(c.bench_profile_path); });
  const double max_speed = c.bench_profile.max_speed_mm_s;
  if (bench.has("speed_mm_s")) {
    c.speed_mm_s = bench.number("speed_mm_s",
                                "a speed in (0, " + num(max_speed) + "] mm/s (the profile's max)",
                                [&](double v) { return v > 0 && v <= max_speed; });
  } else {
    bench.take("speed_mm_s");
  }
  c.home_first = bench.boolean_or("home_first", true);
  bench.reject_unknown("url, profile, speed_mm_s, home_first");

  Section plan = section("plan", true);
  c.plan = read_plan(plan, base_dir, c.bench_profile.soft_limits);

  Section capture = section("capture", true);
  c.camera_spec = capture.string("camera", kCameraForms);
  check_camera_spec(capture, base_dir, &c.camera_spec);
  const std::string calibration =
      capture.string("calibration", "a calibration file, or \"\" for the paper's Sony XC-555");
  if (!calibration.empty()) {
    c.camera_calibration_path =
        existing_file(capture, base_dir, "calibration", "a camera calibration file");
    c.camera = load_named(capture, "calibration", "a camera calibration",
                          [&] { return vision::Camera::load(c.camera_calibration_path); });
  }
  c.frames_per_position = static_cast<int>(capture.integer_or("frames_per_position", 3, 1, 1000));
  c.capture.software_trigger = capture.boolean_or("software_trigger", true);
  c.capture.pixel_format = capture.string_or("pixel_format", "Mono8", "Mono8|Mono10|Mono12|Mono16");
  {
    static const std::set<std::string> kFormats = {"Mono8", "Mono10", "Mono12", "Mono16"};
    if (!kFormats.count(c.capture.pixel_format)) {
      capture.fail("pixel_format", capture.take("pixel_format"),
                   "\"Mono8\", \"Mono10\", \"Mono12\" or \"Mono16\"");
    }
  }
  if (capture.has("exposure_us")) {
    c.capture.exposure_us =
        capture.number("exposure_us", "an exposure time > 0 µs", [](double v) { return v > 0; });
  }
  if (capture.has("gain")) {
    c.capture.gain = capture.number("gain", "a gain >= 0 (camera units, usually dB)",
                                    [](double v) { return v >= 0; });
  }
  c.faults.grab_timeout =
      std::chrono::milliseconds(capture.integer_or("grab_timeout_ms", 2000, 1, 3600000));
  c.faults.capture_retries = static_cast<int>(capture.integer_or("retries", 2, 0, 100));
  c.capture.retries = c.faults.capture_retries;
  const std::string save = capture.string_or("save_frames", "", "a folder path, or \"\"");
  if (!save.empty()) {
    c.frames_dir = resolve(base_dir, save);
    std::error_code ec;
    if (fs::exists(*c.frames_dir, ec) && !fs::is_directory(*c.frames_dir, ec)) {
      capture.fail("save_frames", capture.take("save_frames"), "a folder path, or \"\"",
                   *c.frames_dir + " exists and is not a folder");
    }
  }
  capture.reject_unknown(
      "camera, calibration, frames_per_position, software_trigger, pixel_format, exposure_us, "
      "gain, grab_timeout_ms, retries, save_frames");

  Section settle = section("settle", false);
  c.settle.timeout = std::chrono::milliseconds(
      settle.integer_or("timeout_ms", c.bench_profile.timing.settle_timeout_ms, 1, 3600000));
  c.settle.dwell = std::chrono::milliseconds(settle.integer_or("dwell_ms", 0, 0, 3600000));
  settle.reject_unknown("timeout_ms, dwell_ms");

  Section faults = section("faults", false);
  const std::string on_alarm = faults.string_or("on_alarm", "pause", "\"pause\" or \"abort\"");
  if (on_alarm != "pause" && on_alarm != "abort") {
    faults.fail("on_alarm", faults.take("on_alarm"), "\"pause\" or \"abort\"");
  }
  c.faults.on_alarm = on_alarm == "pause" ? AlarmAction::kPause : AlarmAction::kAbort;
  c.faults.max_consecutive_failed_positions =
      static_cast<int>(faults.integer_or("max_consecutive_failed", 5, 1, 1000000));
  c.faults.link_retries = static_cast<int>(faults.integer_or("link_retries", 3, 0, 100));
  faults.reject_unknown("on_alarm, max_consecutive_failed, link_retries");

  Section target = section("target", true);
  c.target_layout_path = existing_file(target, base_dir, "layout", "a target layout");
  c.target = load_named(target, "layout", "a target layout (vision/target)",
                        [&] { return vision::Target::load(c.target_layout_path); });
  target.reject_unknown("layout");

  Section rig = section("rig", true);
  read_rig(rig, base_dir, &c);

  Section database = section("database", true);
  const std::string db = database.string("path", "the path of the run database");
  if (db.empty()) database.fail("path", database.take("path"), "the path of the run database");
  c.database_path = resolve(base_dir, db);
  {
    std::error_code ec;
    if (fs::is_directory(c.database_path, ec)) {
      database.fail("path", database.take("path"), "the path of the run database file",
                    c.database_path + " is a folder");
    }
  }
  c.durable_commits = database.boolean_or("durable_commits", true);
  database.reject_unknown("path, durable_commits");

  Section telemetry = section("telemetry", false);
  const std::string endpoint = "a ZeroMQ endpoint tcp://HOST:PORT";
  c.telemetry_publish = telemetry.string_or("publish", c.telemetry_publish, endpoint);
  c.telemetry_control = telemetry.string_or("control", c.telemetry_control, endpoint);
  c.telemetry_allow_remote = telemetry.boolean_or("allow_remote", false);
  check_endpoint(telemetry, "publish", c.telemetry_publish, c.telemetry_allow_remote);
  check_endpoint(telemetry, "control", c.telemetry_control, c.telemetry_allow_remote);
  if (c.telemetry_publish == c.telemetry_control) {
    telemetry.fail("control", telemetry.take("control"),
                   "an endpoint different from telemetry.publish (" + c.telemetry_publish + ")");
  }
  telemetry.reject_unknown("publish, control, allow_remote");

  // Consistency of the parts with each other.
  const std::string rig_key = c.rig_geometry_path.empty() ? "target" : "file";
  for (std::size_t i = 0; i < c.plan.size(); ++i) {
    const PlanPosition& p = c.plan.positions()[i];
    const double z_m = c.geometry.T_cam_target(p.x_mm, p.y_mm).t.z();
    if (!(z_m > 0)) {
      rig.fail(rig_key, rig.take(rig_key),
               "a geometry with the target in front of the camera at every plan position",
               "at position " + std::to_string(i) + " (x " + num(p.x_mm) + ", y " + num(p.y_mm) +
                   " mm) the target origin is at z_cam = " + num(z_m) + " m");
    }
  }
  // Every move must be able to finish within the settle timeout. The bound is
  // the time at full speed with no acceleration, so a feasible file always passes.
  const double speed = c.speed_mm_s.value_or(c.bench_profile.default_speed_mm_s);
  PlanPosition from{c.bench_profile.home_x_mm, c.bench_profile.home_y_mm};
  const std::size_t first = c.home_first ? 0 : 1;
  if (!c.home_first && c.plan.size() > 0) from = c.plan.positions()[0];
  for (std::size_t i = first; i < c.plan.size(); ++i) {
    const PlanPosition& to = c.plan.positions()[i];
    const double travel_mm = std::max(std::abs(to.x_mm - from.x_mm), std::abs(to.y_mm - from.y_mm));
    const double move_ms = travel_mm / speed * 1000.0;
    if (move_ms >= static_cast<double>(c.settle.timeout.count())) {
      const std::string where = i == 0
                                    ? "home (x " + num(from.x_mm) + ", y " + num(from.y_mm) + " mm)"
                                    : "position " + std::to_string(i - 1);
      const toml::node* node = settle.take("timeout_ms");
      const std::string expected =
          "a timeout longer than the longest move of the plan: " + num(travel_mm) + " mm from " +
          where + " to position " + std::to_string(i) + " takes at least " + num(move_ms) +
          " ms at " + num(speed) + " mm/s";
      if (node != nullptr) settle.fail("timeout_ms", node, expected);
      throw SweepConfigError(file + ": settle.timeout_ms: absent, so the profile's " +
                             "settle_timeout_ms = " + std::to_string(c.settle.timeout.count()) +
                             " applies: expected " + expected);
    }
    from = to;
  }
  return c;
}

}  // namespace rig::sweep
