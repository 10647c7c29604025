// sim::bench::BenchSimConfig: the physics and faults of the simulated bench, read
// from the [sim] table of a bench file (config/benches/sim.toml). The register
// map it serves is the drive profile of the same file (motion::DriveProfile).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace sim::bench {

// Alarm codes of the simulated drive (docs/register-map.md).
enum AlarmCode : int {
  kAlarmNone = 0,
  kAlarmLimit = 1,           // target outside the travel
  kAlarmFollowingError = 2,  // injected (alarm_at)
  kAlarmNotHomed = 3,        // move before homing
  kAlarmBadCommand = 4,      // unknown command code, zero speed
};

struct AxisConfig {
  double max_speed_mm_s = 100;  // cap on the speed register
  double accel_mm_s2 = 500;     // trapezoid ramps; higher = shorter moves
  double travel_min_mm = -5;    // drive's own limits; targets outside raise kAlarmLimit
  double travel_max_mm = 505;
  // Deadband between motor (what the encoder reads) and carriage (where the
  // camera really is): on a reversal the carriage lags by up to this much.
  double backlash_mm = 0;
  // 1-sigma error of the carriage at each stop, invisible to the encoder
  // (screw pitch error, thermal drift): what makes a real rig's "true"
  // position differ from its read-back.
  double repeatability_mm = 0;
  double initial_mm = 0;  // position at power-up
  // Encoder scale error, parts per million: the encoder reads (1 + ppm 1e-6)
  // times the carriage's true travel from 0, so the carriage stops at
  // target / (1 + ppm 1e-6) (a glass scale ~ +-5 ppm, a rotary encoder on a
  // ball screw with pitch error ~ 20-50 ppm). 0 = exact.
  double encoder_scale_ppm = 0;
  // Thermal drift of the carriage relative to the encoder, um per minute of
  // simulated time since power-up (screw warming: ~0.1-1 um/min in the first
  // hour). 0 = none.
  double thermal_drift_um_per_min = 0;
  // Residual vibration after a stop (the encoder is already in position; the
  // camera on its mount is not): the carriage oscillates along the last move's
  // direction as A exp(-t / tau) cos(2 pi f t) from the stop. A = 0 = none.
  double vibration_amplitude_mm = 0;
  double vibration_frequency_hz = 30;
  double vibration_decay_s = 0.05;
};

// Raise an alarm when the bench passes within radius_mm of (x_mm, y_mm).
struct AlarmAt {
  double x_mm = 0, y_mm = 0, radius_mm = 1;
  int code = kAlarmFollowingError;
};

// Link and drive faults for tests. Counters start when the plan is
// installed (BenchServer construction or inject()); each fault fires once.
struct FaultPlan {
  int drop_after_requests = 0;   // close the connection on the Nth request, unanswered
  int stall_after_requests = 0;  // leave the Nth request unanswered and answer
  double stall_s = 0;            //   nothing at all for stall_s (wall clock)
  double reply_delay_ms = 0;     // every answer this late (wall clock)
  int late_after_requests = 0;   // answer the Nth request, but late_ms late (wall
  double late_ms = 0;            //   clock): past the driver's timeout, a stale reply
  int refuse_writes = 0;         // next N writes: Modbus exception 4 (server failure)
  int ignore_writes = 0;         // next N writes: acknowledged, not stored
  std::optional<AlarmAt> alarm_at;
};

struct BenchSimConfig {
  // Simulated seconds per wall second. 1 = real time; CI sweeps use 10-50 to
  // run faster without changing the logic. Link faults (stall, delay) stay in
  // wall time. Precondition: > 0.
  double time_scale = 1;
  double encoder_resolution_mm = 0.001;  // read-back quantization
  double in_position_band_mm = 0.001;    // in-position bit band around the target
  bool require_homing = true;            // moves before homing raise kAlarmNotHomed
  double homing_speed_mm_s = 50;
  std::uint64_t seed = 1;  // repeatability noise
  AxisConfig x, y;
  FaultPlan faults;
};

// Reads the [sim] table of a bench file; the other tables are the drive
// profile's (motion::load_drive_profile checks them). Throws
// motion::ProfileError "FILE: sim.TABLE.KEY = VALUE: [PROBLEM; ]expected WHAT"
// (config/reader.hpp); an unknown key inside [sim] is refused. A file without
// [sim] gives the defaults above.
BenchSimConfig load_bench_sim_config(const std::string& path);
BenchSimConfig parse_bench_sim_config(std::string_view toml_text, const std::string& source);

}  // namespace sim::bench
