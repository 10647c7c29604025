// Reading the [sim] table of a bench file (see config.hpp).
#include "sim/bench/config.hpp"

#include <cmath>
#include <cstdint>

#include "config/reader.hpp"
#include "motion/errors.hpp"

namespace sim::bench {
namespace {

using config::format_number;

AxisConfig read_axis(config::Table t) {
  AxisConfig a;
  a.max_speed_mm_s = t.number_or("max_speed_mm_s", a.max_speed_mm_s, config::positive());
  a.accel_mm_s2 = t.number_or("accel_mm_s2", a.accel_mm_s2, config::positive());
  a.travel_min_mm = t.number_or("travel_min_mm", a.travel_min_mm);
  a.travel_max_mm = t.number_or("travel_max_mm", a.travel_max_mm);
  a.backlash_mm = t.number_or("backlash_mm", a.backlash_mm, config::non_negative());
  a.repeatability_mm = t.number_or("repeatability_mm", a.repeatability_mm, config::non_negative());
  a.initial_mm = t.number_or("initial_mm", a.initial_mm);
  a.encoder_scale_ppm = t.number_or("encoder_scale_ppm", a.encoder_scale_ppm);
  a.thermal_drift_um_per_min = t.number_or("thermal_drift_um_per_min", a.thermal_drift_um_per_min);
  a.vibration_amplitude_mm =
      t.number_or("vibration_amplitude_mm", a.vibration_amplitude_mm, config::non_negative());
  a.vibration_frequency_hz =
      t.number_or("vibration_frequency_hz", a.vibration_frequency_hz, config::positive());
  a.vibration_decay_s = t.number_or("vibration_decay_s", a.vibration_decay_s, config::positive());
  t.reject_unknown();
  if (std::abs(a.encoder_scale_ppm) > 1e4)
    t.fail("encoder_scale_ppm", "a scale error within -10000 .. 10000 ppm");
  // An absent key's default is named as the problem.
  const auto given = [&](const char* key, double value) {
    return t.has(key) ? std::string() : "not given, so " + format_number(value) + " mm";
  };
  if (!(a.travel_min_mm < a.travel_max_mm)) {
    t.fail("travel_max_mm",
           "a travel_max_mm > travel_min_mm (" + format_number(a.travel_min_mm) + " mm)",
           given("travel_max_mm", a.travel_max_mm));
  }
  if (a.initial_mm < a.travel_min_mm || a.initial_mm > a.travel_max_mm) {
    t.fail("initial_mm",
           "a position within the travel " + format_number(a.travel_min_mm) + ".." +
               format_number(a.travel_max_mm) + " mm",
           given("initial_mm", a.initial_mm));
  }
  return a;
}

FaultPlan read_faults(config::Table f) {
  FaultPlan p;
  const auto count = [&](const char* key) {
    return static_cast<int>(f.integer_or(key, 0, 0, INT32_MAX));
  };
  p.drop_after_requests = count("drop_after_requests");
  p.stall_after_requests = count("stall_after_requests");
  p.stall_s = f.number_or("stall_s", 0, config::non_negative());
  p.reply_delay_ms = f.number_or("reply_delay_ms", 0, config::non_negative());
  p.late_after_requests = count("late_after_requests");
  p.late_ms = f.number_or("late_ms", 0, config::non_negative());
  p.refuse_writes = count("refuse_writes");
  p.ignore_writes = count("ignore_writes");
  config::Table alarm_at = f.optional_table("alarm_at");
  if (alarm_at.exists()) {
    AlarmAt at;
    at.x_mm = alarm_at.number("x_mm");
    at.y_mm = alarm_at.number("y_mm");
    at.radius_mm = alarm_at.number("radius_mm", config::positive());
    at.code = static_cast<int>(alarm_at.integer_or("code", kAlarmFollowingError, 1, 65535));
    alarm_at.reject_unknown();
    p.alarm_at = at;
  }
  f.reject_unknown();
  return p;
}

BenchSimConfig read_sim_table(const config::Document& file) {
  config::Table sim = file.root().optional_table("sim");
  BenchSimConfig c;
  c.time_scale = sim.number_or("time_scale", c.time_scale, config::positive());
  c.encoder_resolution_mm =
      sim.number_or("encoder_resolution_mm", c.encoder_resolution_mm, config::positive());
  c.in_position_band_mm =
      sim.number_or("in_position_band_mm", c.in_position_band_mm, config::non_negative());
  c.require_homing = sim.boolean_or("require_homing", c.require_homing);
  c.homing_speed_mm_s = sim.number_or("homing_speed_mm_s", c.homing_speed_mm_s, config::positive());
  c.seed = static_cast<std::uint64_t>(sim.integer_or("seed", 1, 0, INT64_MAX));
  config::Table x = sim.optional_table("x");
  config::Table y = sim.optional_table("y");
  config::Table faults = sim.optional_table("faults");
  sim.reject_unknown();
  c.x = read_axis(x);
  c.y = read_axis(y);
  c.faults = read_faults(faults);
  return c;
}

}  // namespace

BenchSimConfig parse_bench_sim_config(std::string_view text, const std::string& source) {
  return read_sim_table(
      config::Document::parse<motion::ProfileError>(std::string(text), source, "the bench file"));
}

BenchSimConfig load_bench_sim_config(const std::string& path) {
  return read_sim_table(config::Document::read<motion::ProfileError>(path, "the bench file"));
}

}  // namespace sim::bench
