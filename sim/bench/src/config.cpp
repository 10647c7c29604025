// Reading the [sim] table of a bench file (see bench_config.hpp).
#include "sim/bench/config.hpp"

#include "motion/errors.hpp"
#include "motion/toml_reader.hpp"

namespace sim::bench {
namespace {

using motion::TomlTableReader;

AxisConfig read_axis(const toml::table& root, const std::string& source, const std::string& path) {
  TomlTableReader r(root, source, path, /*optional=*/true);
  AxisConfig a;
  a.max_speed_mm_s = r.positive_or("max_speed_mm_s", a.max_speed_mm_s);
  a.accel_mm_s2 = r.positive_or("accel_mm_s2", a.accel_mm_s2);
  a.travel_min_mm = r.number_or("travel_min_mm", a.travel_min_mm);
  a.travel_max_mm = r.number_or("travel_max_mm", a.travel_max_mm);
  a.backlash_mm = r.non_negative_or("backlash_mm", a.backlash_mm);
  a.repeatability_mm = r.non_negative_or("repeatability_mm", a.repeatability_mm);
  a.initial_mm = r.number_or("initial_mm", a.initial_mm);
  r.reject_unknown();
  if (!(a.travel_min_mm < a.travel_max_mm)) r.fail("travel_max_mm", "must be > travel_min_mm");
  if (a.initial_mm < a.travel_min_mm || a.initial_mm > a.travel_max_mm) {
    r.fail("initial_mm", "must lie within the travel");
  }
  return a;
}

}  // namespace

BenchSimConfig parse_bench_sim_config(std::string_view text, const std::string& source) {
  const toml::table root = motion::parse_toml(text, source);
  BenchSimConfig c;
  TomlTableReader r(root, source, "sim", /*optional=*/true);
  c.time_scale = r.positive_or("time_scale", c.time_scale);
  c.encoder_resolution_mm = r.positive_or("encoder_resolution_mm", c.encoder_resolution_mm);
  c.in_position_band_mm = r.non_negative_or("in_position_band_mm", c.in_position_band_mm);
  c.require_homing = r.boolean_or("require_homing", c.require_homing);
  c.homing_speed_mm_s = r.positive_or("homing_speed_mm_s", c.homing_speed_mm_s);
  c.seed = static_cast<std::uint64_t>(r.integer_or("seed", 1, 0, INT64_MAX));
  r.sub_table("x");
  r.sub_table("y");
  r.sub_table("faults");
  r.reject_unknown();
  c.x = read_axis(root, source, "sim.x");
  c.y = read_axis(root, source, "sim.y");

  TomlTableReader f(root, source, "sim.faults", /*optional=*/true);
  FaultPlan& p = c.faults;
  p.drop_after_requests = static_cast<int>(f.integer_or("drop_after_requests", 0, 0, INT32_MAX));
  p.stall_after_requests = static_cast<int>(f.integer_or("stall_after_requests", 0, 0, INT32_MAX));
  p.stall_s = f.non_negative_or("stall_s", 0);
  p.reply_delay_ms = f.non_negative_or("reply_delay_ms", 0);
  p.refuse_writes = static_cast<int>(f.integer_or("refuse_writes", 0, 0, INT32_MAX));
  p.ignore_writes = static_cast<int>(f.integer_or("ignore_writes", 0, 0, INT32_MAX));
  if (f.sub_table("alarm_at")) {
    TomlTableReader a(root, source, "sim.faults.alarm_at");
    AlarmAt at;
    at.x_mm = a.number("x_mm");
    at.y_mm = a.number("y_mm");
    at.radius_mm = a.positive("radius_mm");
    at.code = static_cast<int>(a.integer_or("code", kAlarmFollowingError, 1, 65535));
    a.reject_unknown();
    p.alarm_at = at;
  }
  f.reject_unknown();
  return c;
}

BenchSimConfig load_bench_sim_config(const std::string& path) {
  return parse_bench_sim_config(motion::read_text_file(path, "the bench file"), path);
}

}  // namespace sim::bench
