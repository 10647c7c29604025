// Reading and validating sweep files (see sweep_config.hpp).
#include "rig/sweep/sweep_config.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <vector>

#include "config/reader.hpp"
#include "motion/bench_url.hpp"
#include "rig/sweep/pose_json.hpp"
#include "rig/telemetry/telemetry.hpp"
#include "vision/detectors.hpp"

namespace rig::sweep {
namespace {

namespace fs = std::filesystem;
using config::Table;

constexpr const char* kCameraForms =
    "a camera spec gige:ADDRESS | gige:ID | v4l2:PATH | replay:DIR";
constexpr const char* kBenchForms =
    "a bench URL modbus-tcp://HOST:PORT or modbus-rtu:///dev/DEVICE?baud=...";

// Runs `load`, turning any error of the file it reads into a SweepConfigError
// that names the sweep file and the key, then quotes the cause.
template <typename Load>
auto load_named(const Table& t, const std::string& key, const std::string& what, Load load) {
  try {
    return load();
  } catch (const std::exception& e) {
    t.fail(key, what, std::string("it does not load: ") + e.what());
  }
}

// Of the keys of every kind of plan, only the given kind's may be present.
void check_plan_kind(const Table& s, const std::string& kind) {
  const std::vector<std::pair<std::string, std::set<std::string>>> kinds = {
      {"grid", {"x_mm", "y_mm", "serpentine"}}, {"csv", {"file"}}, {"paper", {"x_mm", "y_mm"}}};
  const auto own =
      std::find_if(kinds.begin(), kinds.end(), [&](const auto& k) { return k.first == kind; });
  for (const auto& [other, keys] : kinds) {
    for (const std::string& key : keys) {
      if (!own->second.count(key) && s.has(key)) {
        s.fail(key, "exactly one kind of plan",
               "plan." + key + " belongs to kind = \"" + other + "\", not \"" + kind + "\"");
      }
    }
  }
}

SweepPlan read_grid(Table& s) {
  const std::string expected = "[min, max, step] in mm with min <= max and step > 0";
  const std::vector<double> x = s.numbers("x_mm", 3, 3, expected);
  if (x[1] < x[0] || x[2] <= 0) s.fail("x_mm", expected);
  const std::vector<double> y = s.numbers("y_mm", 3, 3, expected);
  if (y[1] < y[0] || y[2] <= 0) s.fail("y_mm", expected);
  const bool serpentine = s.boolean_or("serpentine", true);
  return load_named(s, "x_mm",
                    "a grid of at most " + std::to_string(SweepPlan::kMaxPositions) + " positions",
                    [&] {
                      return SweepPlan::grid({x[0], x[1], x[2], y[0], y[1], y[2], serpentine});
                    });
}

SweepPlan read_paper(Table& s, const motion::SoftLimits& limits) {
  const std::string expected = "[min, max] in mm with min < max";
  std::vector<double> x = {limits.x_min_mm, limits.x_max_mm};
  std::vector<double> y = {limits.y_min_mm, limits.y_max_mm};
  if (s.has("x_mm")) x = s.numbers("x_mm", 2, 2, expected);
  if (!(x[0] < x[1])) s.fail("x_mm", expected);
  if (s.has("y_mm")) y = s.numbers("y_mm", 2, 2, expected);
  if (!(y[0] < y[1])) s.fail("y_mm", expected);
  return SweepPlan::paper(x[0], x[1], y[0], y[1]);
}

// Every position inside the soft limits, before anything moves.
void check_inside_soft_limits(const Table& s, const std::string& kind, const SweepPlan& plan,
                              const motion::SoftLimits& limits) {
  for (std::size_t i = 0; i < plan.size(); ++i) {
    const PlanPosition& p = plan.positions()[i];
    if (limits.contains(p.x_mm, p.y_mm)) continue;
    const bool x_inside = p.x_mm >= limits.x_min_mm && p.x_mm <= limits.x_max_mm;
    s.fail(kind == "csv" ? "file"
           : x_inside    ? "y_mm"
                         : "x_mm",
           "every position inside the bench's soft limits x " +
               config::format_number(limits.x_min_mm) + ".." +
               config::format_number(limits.x_max_mm) + " mm, y " +
               config::format_number(limits.y_min_mm) + ".." +
               config::format_number(limits.y_max_mm) + " mm",
           "position " + std::to_string(i) + " (x " + config::format_number(p.x_mm) + ", y " +
               config::format_number(p.y_mm) + " mm) is outside");
  }
}

SweepPlan read_plan(Table s, const motion::SoftLimits& limits) {
  const std::string kind = s.choice("kind", {"grid", "csv", "paper"});
  check_plan_kind(s, kind);
  SweepPlan plan;
  if (kind == "grid") {
    plan = read_grid(s);
  } else if (kind == "csv") {
    const std::string path = s.existing_file("file", "a CSV plan (x_mm,y_mm)");
    plan = load_named(s, "file", "a CSV plan", [&] { return SweepPlan::from_csv(path); });
  } else {
    plan = read_paper(s, limits);
  }
  s.reject_unknown("one of kind, x_mm, y_mm, serpentine, file");
  check_inside_soft_limits(s, kind, plan, limits);
  return plan;
}

// The bench first: the plan, speed and settle timeout are checked against its profile.
void read_bench(Table bench, SweepConfig* c) {
  const std::string url = bench.string("url", kBenchForms);
  c->bench_url =
      load_named(bench, "url", "a valid bench URL", [&] { return motion::BenchUrl::parse(url); });
  c->bench_profile_path = bench.existing_file("profile", "a drive profile");
  c->bench_profile = load_named(bench, "profile", "a drive profile (motion/drive_profile)",
                                [&] { return motion::load_drive_profile(c->bench_profile_path); });
  const double max_speed = c->bench_profile.max_speed_mm_s;
  c->speed_mm_s = bench.optional_number(
      "speed_mm_s",
      {"a speed in (0, " + config::format_number(max_speed) + "] mm/s (the profile's max)",
       [&](double v) { return v > 0 && v <= max_speed; }});
  c->home_first = bench.boolean_or("home_first", true);
  bench.reject_unknown();
}

void check_camera_spec(const Table& s, std::string* spec) {
  const auto colon = spec->find(':');
  const std::string scheme = colon == std::string::npos ? "" : spec->substr(0, colon);
  const std::string rest = colon == std::string::npos ? "" : spec->substr(colon + 1);
  if ((scheme != "gige" && scheme != "v4l2" && scheme != "replay") || rest.empty()) {
    s.fail("camera", kCameraForms);
  }
  if (scheme == "replay") {
    // Recorded frames are data next to the sweep file: resolve and require them now.
    const std::string dir = s.resolve(rest);
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) {
      s.fail("camera", "replay:DIR with an existing folder", dir + " is not a folder");
    }
    *spec = "replay:" + dir;
  }
}

void read_camera(Table& capture, SweepConfig* c) {
  c->camera_spec = capture.string("camera", kCameraForms);
  check_camera_spec(capture, &c->camera_spec);
  const std::string calibration =
      capture.string("calibration", "a calibration file, or \"\" for the paper's Sony XC-555");
  if (!calibration.empty()) {
    c->camera_calibration_path = capture.existing_file("calibration", "a camera calibration file");
    c->camera = load_named(capture, "calibration", "a camera calibration",
                           [&] { return vision::Camera::load(c->camera_calibration_path); });
  }
}

void read_capture(Table capture, SweepConfig* c) {
  read_camera(capture, c);
  c->frames_per_position = static_cast<int>(capture.integer_or("frames_per_position", 3, 1, 1000));
  c->capture.software_trigger = capture.boolean_or("software_trigger", true);
  c->capture.pixel_format = capture.choice_or(
      "pixel_format", "Mono8", {"Mono8", "Mono10", "Mono12", "Mono12Packed", "Mono16", "BayerRG8"});
  c->capture.exposure_us = capture.optional_number(
      "exposure_us", {"an exposure time > 0 µs", [](double v) { return v > 0; }});
  c->capture.gain = capture.optional_number(
      "gain", {"a gain >= 0 (camera units, usually dB)", [](double v) { return v >= 0; }});
  if (const auto packet = capture.optional_number(
          "packet_size", {"a GigE Vision packet size in bytes, an integer 576..9000 (1500 on a "
                          "standard MTU; more needs jumbo frames)",
                          [](double v) { return v >= 576 && v <= 9000 && v == std::floor(v); }}))
    c->capture.packet_size_bytes = static_cast<int>(*packet);
  c->capture.inter_packet_delay_ns = capture.optional_number(
      "inter_packet_delay_ns", {"a GigE Vision inter-packet delay in ns, 0..1e8",
                                [](double v) { return v >= 0 && v <= 1e8; }});
  c->grab_timeout = std::chrono::milliseconds(
      capture.integer_or("grab_timeout_ms", c->grab_timeout.count(), 1, 3600000));
  c->capture.retries = static_cast<int>(capture.integer_or("retries", 2, 0, 100));
  const std::string save = capture.string_or("save_frames", "", "a folder path, or \"\"");
  if (!save.empty()) {
    c->frames_dir = capture.resolve(save);
    std::error_code ec;
    if (fs::exists(*c->frames_dir, ec) && !fs::is_directory(*c->frames_dir, ec)) {
      capture.fail("save_frames", "a folder path, or \"\"",
                   *c->frames_dir + " exists and is not a folder");
    }
  }
  capture.reject_unknown();
}

void read_settle(Table settle, SweepConfig* c) {
  c->settle.timeout = std::chrono::milliseconds(
      settle.integer_or("timeout_ms", c->bench_profile.timing.settle_timeout_ms, 1, 3600000));
  c->settle.dwell = std::chrono::milliseconds(settle.integer_or("dwell_ms", 0, 0, 3600000));
  settle.reject_unknown();
}

void read_faults(Table faults, SweepConfig* c) {
  c->faults.on_alarm = faults.choice_or("on_alarm", "pause", {"pause", "abort"}) == "pause"
                           ? AlarmAction::kPause
                           : AlarmAction::kAbort;
  c->faults.max_consecutive_failed_positions =
      static_cast<int>(faults.integer_or("max_consecutive_failed", 5, 1, 1000000));
  c->faults.link_retries = static_cast<int>(faults.integer_or("link_retries", 3, 0, 100));
  c->faults.camera_reopen_timeout = std::chrono::milliseconds(faults.integer_or(
      "camera_reopen_timeout_ms", c->faults.camera_reopen_timeout.count(), 0, 3600000));
  c->faults.camera_reopen_interval = std::chrono::milliseconds(faults.integer_or(
      "camera_reopen_interval_ms", c->faults.camera_reopen_interval.count(), 1, 600000));
  faults.reject_unknown();
}

void read_compute(Table compute, SweepConfig* c) {
  c->compute_threads = static_cast<int>(
      compute.integer_or("threads", default_compute_threads(), 1, FramePool::kMaxThreads));
  compute.reject_unknown();
}

void read_target(Table target, SweepConfig* c) {
  c->target_layout_path = target.existing_file("layout", "a target layout");
  c->target = load_named(target, "layout", "a target layout (vision/target)",
                         [&] { return vision::Target::load(c->target_layout_path); });
  target.reject_unknown();
}

// [detect] detectors: each a detector of vision's registry that decodes the
// target's family, once; absent = every such detector. A family no detector
// decodes is refused here, before the bench moves.
void read_detect(Table detect, const Table& target, SweepConfig* c) {
  const std::string& family = c->target.family;
  const std::vector<std::string> able = vision::detectors_for_family(family);
  if (able.empty()) {
    target.fail("layout",
                "a target whose marker family a detector decodes (" +
                    vision::detector_names_text() + " read the families of vision/detectors.hpp)",
                "marker family \"" + family + "\" is read by no detector");
  }
  c->detectors = able;
  if (!detect.exists() || !detect.has("detectors")) {
    if (detect.exists()) detect.reject_unknown();
    return;
  }
  std::string able_text;
  for (const std::string& d : able)
    able_text += (able_text.empty() ? "\"" : ", \"") + d + "\"";
  const std::string expected =
      "detectors that decode the target's family " + family + ": " + able_text;
  c->detectors = detect.strings("detectors", 1, able.size(), expected);
  std::set<std::string> seen;
  for (const std::string& d : c->detectors) {
    if (!vision::detector_reads(d, family))
      detect.fail("detectors", expected, "\"" + d + "\" does not decode it");
    if (!seen.insert(d).second) detect.fail("detectors", expected, "\"" + d + "\" twice");
  }
  detect.reject_unknown();
  std::vector<std::string> ordered;  // the measurer's order: the primary first
  for (const std::string& d : able)
    if (seen.count(d) != 0) ordered.push_back(d);
  c->detectors = ordered;
}

// The geometry from a rig file or from inline [rig.camera_mount] / [rig.target].
void read_rig(Table& rig, SweepConfig* c) {
  const bool inline_tables = rig.has("camera_mount") || rig.has("target");
  const std::string one_of =
      "exactly one of rig.file = \"RIG.toml\" or the tables [rig.camera_mount] and [rig.target]";
  if (!rig.has("file") && !inline_tables) rig.fail("file", one_of);
  if (rig.has("file") && inline_tables) rig.fail("file", one_of, "inline rig tables are given too");
  if (rig.has("file")) {
    c->rig_geometry_path = rig.existing_file("file", "a rig file (vision/rig_geometry)");
    c->geometry = load_named(rig, "file", "a rig file", [&] {
      const config::Document file =
          config::Document::read<vision::RigConfigError>(c->rig_geometry_path, "the rig file");
      c->rig_geometry_text = file.text();
      return vision::RigGeometry::load(file);
    });
  } else {
    c->geometry = vision::RigGeometry::read(rig);
    c->rig_geometry_text = rig.to_toml();
  }
  rig.reject_unknown("one of file, camera_mount, target");
}

void read_database(Table database, SweepConfig* c) {
  const std::string db = database.string("path", "the path of the run database");
  if (db.empty()) database.fail("path", "the path of the run database");
  c->database_path = database.resolve(db);
  std::error_code ec;
  if (fs::is_directory(c->database_path, ec)) {
    database.fail("path", "the path of the run database file", c->database_path + " is a folder");
  }
  c->durable_commits = database.boolean_or("durable_commits", true);
  database.reject_unknown();
}

// The endpoint checked by the rules the telemetry itself binds by
// (rig/telemetry/telemetry.hpp), reported as a sweep file error.
void check_endpoint(const Table& t, const std::string& key, const std::string& endpoint,
                    bool allow_remote) {
  try {
    telemetry::validate_endpoint(endpoint, allow_remote, "endpoint");
  } catch (const telemetry::EndpointError& e) {
    t.fail(key,
           "an endpoint tcp://HOST:PORT, ipc://PATH or inproc://NAME on this machine unless "
           "telemetry.allow_remote = true",
           e.what());
  }
}

// The endpoints, checked here (each error naming its key) by the rules
// telemetry::validate_endpoints applies.
void read_telemetry(Table t, SweepConfig* c) {
  const std::string endpoint = "a ZeroMQ endpoint tcp://HOST:PORT";
  telemetry::TelemetryEndpoints& e = c->telemetry;
  e.publish = t.string_or("publish", e.publish, endpoint);
  e.control = t.string_or("control", e.control, endpoint);
  e.allow_remote = t.boolean_or("allow_remote", e.allow_remote);
  check_endpoint(t, "publish", e.publish, e.allow_remote);
  check_endpoint(t, "control", e.control, e.allow_remote);
  if (e.publish == e.control) {
    t.fail("control", "an endpoint different from telemetry.publish (" + e.publish + ")");
  }
  t.reject_unknown();
}

// A program name (looked up on PATH) or a path: the file it names, or "" when
// there is no executable file of that name.
std::string find_program(const std::string& program, const fs::path& folder) {
  std::error_code ec;
  const auto executable = [&](const fs::path& p) {
    return fs::is_regular_file(p, ec) && ::access(p.c_str(), X_OK) == 0;
  };
  if (program.find('/') != std::string::npos) {
    const fs::path p = fs::path(program).is_absolute() ? fs::path(program) : folder / program;
    return executable(p) ? p.lexically_normal().string() : "";
  }
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  for (std::size_t start = 0; start <= dirs.size();) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const fs::path candidate = fs::path(dirs.substr(start, end - start)) / program;
    if (end > start && executable(candidate)) return candidate.string();
    start = end + 1;
  }
  return "";
}

estimator::EstimatorSpec read_estimator(Table& e, const std::set<std::string>& taken) {
  estimator::EstimatorSpec spec;
  const std::string name_rule = "a name of 1..64 characters A-Z a-z 0-9 _ . -";
  spec.name = e.string("name", name_rule);
  const bool name_ok =
      !spec.name.empty() && spec.name.size() <= 64 &&
      std::all_of(spec.name.begin(), spec.name.end(), [](char ch) {
        return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '.' || ch == '-';
      });
  if (!name_ok) e.fail("name", name_rule);
  if (taken.count(spec.name)) e.fail("name", "a name no other [[estimator]] has", "used twice");
  const std::string argv_rule = "the command as an array of 1..256 strings, program first";
  spec.command = e.strings("command", 1, 256, argv_rule);
  spec.working_dir = fs::path(e.resolve(".")).lexically_normal().string();
  if (spec.working_dir.size() > 1 && spec.working_dir.back() == '/') spec.working_dir.pop_back();
  if (spec.command[0].empty()) e.fail("command", argv_rule, "the program is \"\"");
  if (find_program(spec.command[0], spec.working_dir).empty())
    e.fail("command", argv_rule,
           "\"" + spec.command[0] + "\" is not an executable file" +
               (spec.command[0].find('/') != std::string::npos
                    ? " (relative to " + spec.working_dir + ")"
                    : " on PATH"));
  spec.timeout = std::chrono::milliseconds(e.integer_or("timeout_ms", 2000, 1, 600000));
  spec.startup_timeout =
      std::chrono::milliseconds(e.integer_or("startup_timeout_ms", 10000, 1, 600000));
  spec.max_restarts = static_cast<int>(e.integer_or("max_restarts", 3, 0, 1000));
  spec.send_corners = e.boolean_or("send_corners", true);
  e.reject_unknown();
  return spec;
}

// [[estimator]] tables, when there are any.
void read_estimators(Table& root, SweepConfig* c) {
  if (!root.has("estimator")) return;
  std::set<std::string> names;
  for (Table& e : root.tables("estimator", "[[estimator]] tables with name and command")) {
    c->estimators.push_back(read_estimator(e, names));
    names.insert(c->estimators.back().name);
  }
}

// The target in front of the camera (z_cam > 0) at every plan position.
void check_target_in_front(const Table& rig, const SweepConfig& c) {
  const std::string rig_key = c.rig_geometry_path.empty() ? "target" : "file";
  for (std::size_t i = 0; i < c.plan.size(); ++i) {
    const PlanPosition& p = c.plan.positions()[i];
    const double z_m = c.geometry.T_cam_target(p.x_mm, p.y_mm).t.z();
    if (!(z_m > 0)) {
      rig.fail(rig_key, "a geometry with the target in front of the camera at every plan position",
               "at position " + std::to_string(i) + " (x " + config::format_number(p.x_mm) +
                   ", y " + config::format_number(p.y_mm) +
                   " mm) the target origin is at z_cam = " + config::format_number(z_m) + " m");
    }
  }
}

// Every move must be able to finish within the settle timeout. The bound is
// the time at full speed with no acceleration, so a feasible file always passes.
void check_settle_timeout(const Table& settle, const SweepConfig& c) {
  const double speed = c.speed_mm_s.value_or(c.bench_profile.default_speed_mm_s);
  PlanPosition from{c.bench_profile.home_x_mm, c.bench_profile.home_y_mm};
  const std::size_t first = c.home_first ? 0 : 1;
  if (!c.home_first && c.plan.size() > 0) from = c.plan.positions()[0];
  for (std::size_t i = first; i < c.plan.size(); ++i) {
    const PlanPosition& to = c.plan.positions()[i];
    const double travel_mm = std::max(std::abs(to.x_mm - from.x_mm), std::abs(to.y_mm - from.y_mm));
    const double move_ms = travel_mm / speed * 1000.0;
    if (move_ms >= static_cast<double>(c.settle.timeout.count())) {
      const std::string where = i == 0 ? "home (x " + config::format_number(from.x_mm) + ", y " +
                                             config::format_number(from.y_mm) + " mm)"
                                       : "position " + std::to_string(i - 1);
      settle.fail("timeout_ms",
                  "a timeout longer than the longest move of the plan: " +
                      config::format_number(travel_mm) + " mm from " + where + " to position " +
                      std::to_string(i) + " takes at least " + config::format_number(move_ms) +
                      " ms at " + config::format_number(speed) + " mm/s",
                  settle.has("timeout_ms")
                      ? ""
                      : "absent, so the profile's settle_timeout_ms = " +
                            std::to_string(c.settle.timeout.count()) + " applies");
    }
    from = to;
  }
}

template <typename T>
nlohmann::json optional_json(const std::optional<T>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

}  // namespace

nlohmann::json SweepConfig::estimators_json() const {
  nlohmann::json out = nlohmann::json::array();
  for (const estimator::EstimatorSpec& e : estimators)
    out.push_back({{"name", e.name},
                   {"solver", e.solver_name()},
                   {"command", e.command},
                   {"working_dir", e.working_dir},
                   {"timeout_ms", e.timeout.count()},
                   {"startup_timeout_ms", e.startup_timeout.count()},
                   {"max_restarts", e.max_restarts},
                   {"send_corners", e.send_corners}});
  return out;
}

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
        {"packet_size", optional_json(capture.packet_size_bytes)},
        {"inter_packet_delay_ns", optional_json(capture.inter_packet_delay_ns)},
        {"grab_timeout_ms", grab_timeout.count()},
        {"retries", capture.retries},
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
        {"k3", d.k3},
        {"s1", d.s1},
        {"s2", d.s2},
        {"s3", d.s3},
        {"s4", d.s4}}},
      {"bench",
       {{"url", bench_url.str()},
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
        {"link_retries", faults.link_retries},
        {"camera_reopen_timeout_ms", faults.camera_reopen_timeout.count()},
        {"camera_reopen_interval_ms", faults.camera_reopen_interval.count()}}},
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
      {"detect", {{"detectors", detectors}}},
      {"database", {{"path", database_path}, {"durable_commits", durable_commits}}},
      {"telemetry",
       {{"publish", telemetry.publish},
        {"control", telemetry.control},
        {"allow_remote", telemetry.allow_remote}}},
      {"compute", {{"threads", compute_threads}}},
      {"estimators", estimators_json()},
  };
}

SweepConfig load_sweep_config(const std::string& path) {
  SweepConfig c;
  c.sweep_file = fs::absolute(path).lexically_normal().string();
  const config::Document file =
      config::Document::read<SweepConfigError>(c.sweep_file, "the sweep file");
  c.sweep_file_text = file.text();
  Table root = file.root();
  // Unknown tables first: a misspelt [setle] must not let its defaults be checked.
  for (const char* name : {"plan", "capture", "bench", "settle", "faults", "target", "detect",
                           "rig", "database", "telemetry", "compute", "estimator"}) {
    root.ignore(name);
  }
  root.reject_unknown(
      "one of the tables [plan], [capture], [bench], [settle], [faults], [target], [detect], "
      "[rig], [database], [telemetry], [compute], [[estimator]]");
  read_bench(root.table("bench"), &c);
  c.plan = read_plan(root.table("plan"), c.bench_profile.soft_limits);
  read_capture(root.table("capture"), &c);
  const Table settle = root.optional_table("settle");
  read_settle(settle, &c);
  read_faults(root.optional_table("faults"), &c);
  const Table target = root.table("target");
  read_target(target, &c);
  read_detect(root.optional_table("detect"), target, &c);
  Table rig = root.table("rig");
  read_rig(rig, &c);
  read_database(root.table("database"), &c);
  read_telemetry(root.optional_table("telemetry"), &c);
  read_compute(root.optional_table("compute"), &c);
  read_estimators(root, &c);
  // Consistency of the parts with each other.
  check_target_in_front(rig, c);
  check_settle_timeout(settle, c);
  return c;
}

}  // namespace rig::sweep
