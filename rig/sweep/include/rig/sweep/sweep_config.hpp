// rig::sweep::SweepConfig: everything one sweep needs, read from a sweep file (TOML,
// config/sweeps/*.toml) and validated completely before the bench moves.
//
// Sweep file format. Tables and keys not listed are errors (a misspelt key
// must never fall back to a default); keys marked (required) must be present.
// Relative paths are relative to the sweep file's folder. Lengths in mm,
// times in ms.
//
//   [plan]                      exactly one kind; the keys of another kind are errors
//   kind = "grid"               (required) "grid" | "csv" | "paper"
//   x_mm = [0, 900, 15]         grid (required): [min, max, step]; paper: [min, max],
//   y_mm = [100, 200, 50]         default the bench profile's soft limits
//   serpentine = true           grid: reverse every other row (default true)
//   file = "../plans/x.csv"     csv (required): header "x_mm,y_mm", one "X,Y" per line
//
//   [capture]
//   camera = "gige:127.0.0.1"   (required) gige:ADDRESS|gige:ID|v4l2:PATH|replay:DIR
//   calibration = ""            (required) calibration file; "" = the paper's Sony XC-555
//   frames_per_position = 3     1..1000 (default 3); N > 1 separates jitter from bias
//   software_trigger = true     default true (one exposure per trigger, after settling)
//   pixel_format = "Mono8"      Mono8 | Mono10 | Mono12 | Mono12Packed | Mono16 | BayerRG8
//                               (default Mono8; vision/pixel_format.hpp: the conversions)
//   exposure_us = 10000         > 0; absent keeps the camera's value
//   gain = 0                    >= 0, camera units (dB); absent keeps the camera's value
//   packet_size = 1500          GigE GevSCPSPacketSize, bytes, 576..9000; absent keeps the camera's
//   inter_packet_delay_ns = 0   GigE GevSCPD, ns, 0..1e8; absent keeps the camera's
//   grab_timeout_ms = 2000      > 0 (default 2000): wait for one frame
//   retries = 2                 0..100 (default 2): re-triggers after a timeout or an
//                               incomplete frame before the position is marked failed
//   save_frames = ""            folder for raw frames as PNG; "" = do not save (default)
//
//   [bench]
//   url = "modbus-tcp://127.0.0.1:1502"   (required) motion/bench_url.hpp
//   profile = "../benches/sim.toml"       (required) drive profile
//   speed_mm_s = 100            (0, profile max]; absent = the profile's default speed
//   home_first = true           home the bench before the first move (default true)
//
//   [settle]
//   timeout_ms = 25000          > 0; wait_settled timeout per move (default: the
//                               profile's settle_timeout_ms)
//   dwell_ms = 0                >= 0 (default 0): extra wait after settling
//
//   [faults]
//   on_alarm = "pause"          "pause" | "abort" (default "pause")
//   max_consecutive_failed = 5  1..1000000 (default 5): then the run is aborted
//   link_retries = 3            0..100 (default 3): reconnects after a bench link drop
//
//   [target]
//   layout = "../targets/paper.toml"      (required) vision/target.hpp
//
//   [detect]
//   detectors = ["rig", "aruco:subpix"]  detectors of vision/detectors.hpp, each once, that
//                               decode the target's family; absent = every one that does.
//                               Every detector runs on every frame, every solver on each
//                               one's corners; the first in registry order is the primary
//                               (its corners go to external estimators)
//
//   [rig]                       exactly one of:
//   file = "../rigs/sim.toml"   a rig file (vision/rig_geometry.hpp), or inline tables
//   [rig.camera_mount]          offset_mm = [x, y, z], misalignment_deg = [rx, ry, rz]
//   [rig.target]                origin_mm = [x, y, z], tilt_deg = [rx, ry, rz]
//
//   [database]
//   path = "../../out/ci/run.db"          (required) `rig sweep --db` overrides
//   durable_commits = true      fsync every position (default true)
//
//   [telemetry]
//   publish = "tcp://127.0.0.1:5556"      PUB endpoint (default as shown)
//   control = "tcp://127.0.0.1:5557"      REP endpoint (default as shown), != publish
//   allow_remote = false        false: endpoints must be loopback (127.x, localhost)
//
//   [compute]
//   threads = 2                 1..256 (default: the machine's hardware threads):
//                               frames measured in parallel (rig/sweep/frame_pool.hpp);
//                               the results are the same for any value
//
//   [[estimator]]               zero or more external estimators (docs/external-estimators.md)
//   name = "my_pnp"             (required) [A-Za-z0-9_.-], 1..64 characters, unique;
//                               stored and reported as solver "ext:my_pnp"
//   command = ["python3", "x.py"]  (required) argv, 1..256 strings, no shell; run in
//                               the sweep file's folder; argv[0] a program on PATH
//                               or a path (relative to the sweep file's folder)
//   timeout_ms = 2000           1..600000 (default 2000): per frame, request to answer
//   startup_timeout_ms = 10000  1..600000 (default 10000): start to handshake
//   max_restarts = 3            0..1000 (default 3): restarts per sweep after failures
//   send_corners = true         send rig's detected corners with each frame (default true)
//
// Consistency checks: every plan position inside the profile's soft limits;
// the speed at most the profile's max; the target in front of the camera
// (z_cam > 0) at every position; the settle timeout longer than the plan's
// longest move at the speed (distance / speed, a lower bound that ignores
// acceleration, from the home position when home_first); publish != control;
// every named file exists and parses (its own error is quoted).
#pragma once

#include <chrono>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "config/error.hpp"
#include "motion/bench_url.hpp"
#include "motion/drive_profile.hpp"
#include "rig/estimator/external_estimator.hpp"
#include "rig/sweep/frame_pool.hpp"
#include "rig/sweep/sweep_plan.hpp"
#include "rig/telemetry/telemetry.hpp"
#include "vision/camera.hpp"
#include "vision/frame_source.hpp"
#include "vision/rig_geometry.hpp"
#include "vision/target.hpp"

namespace rig::sweep {

// A sweep file that cannot be used. The message names the sweep file, the key
// and its value as written, and what was expected:
//   "/abs/ci.toml: capture.frames_per_position = 0: expected an integer in 1..1000"
//   "/abs/ci.toml: bench.url: missing; expected a bench URL modbus-tcp://HOST:PORT ..."
// Errors of the files it names (profile, calibration, layout, rig, CSV plan)
// are wrapped: the message names the sweep file and key, then quotes the cause.
// A config::ConfigError: bad input.
class SweepConfigError : public config::ConfigError {
 public:
  using config::ConfigError::ConfigError;
};

struct SettlePolicy {
  // wait_settled timeout per move (default: the profile's settle_timeout_ms).
  // Longer rides out slow long moves; shorter reports a stuck axis sooner.
  std::chrono::milliseconds timeout{25000};
  // Extra wait after the bench reports settled, before the first trigger.
  // Lets vibration of a long camera arm die out; adds to every position.
  std::chrono::milliseconds dwell{0};
};

enum class AlarmAction { kPause, kAbort };

struct FaultPolicy {
  // Bench alarm: stop, record, then pause (wait for `rig ctl resume`) or abort.
  AlarmAction on_alarm = AlarmAction::kPause;
  // Failed positions in a row after which the run is aborted (something is
  // structurally wrong: camera unplugged, target fallen over).
  int max_consecutive_failed_positions = 5;
  // Bench link drop: reconnect attempts (each within the profile's reconnect
  // timeout) before the run fails.
  int link_retries = 3;
  // Camera lost at a position (a grab or trigger fails after the capture's
  // own retries): the camera is closed and opened again, one attempt every
  // camera_reopen_interval, until one opens and delivers a frame of the
  // calibration's size or camera_reopen_timeout has passed since the loss;
  // then the position's frames are taken again. 0 never reopens: the
  // position fails at once. A camera that does not come back within the
  // timeout fails the position (and counts towards
  // max_consecutive_failed_positions).
  std::chrono::milliseconds camera_reopen_timeout{10000};
  std::chrono::milliseconds camera_reopen_interval{500};
};

struct SweepConfig {
  std::string sweep_file;       // absolute path of the file read
  std::string sweep_file_text;  // its bytes (stored in the run)
  SweepPlan plan;
  // Frames taken at each position, 1..1000. N > 1 separates the estimate's
  // jitter (spread over the N frames) from its bias; each frame adds a
  // trigger-to-frame time (~exposure + transfer) per position.
  int frames_per_position = 3;
  // Move speed, mm/s, in (0, profile max]; unset = the profile's default.
  // Faster sweeps; slower moves ring less and settle sooner.
  std::optional<double> speed_mm_s;
  // Home the bench before the first move. false skips homing (which takes
  // minutes on some drives) when the bench is known to be homed; the first
  // move then starts wherever the bench stands.
  bool home_first = true;
  SettlePolicy settle;
  FaultPolicy faults;
  motion::BenchUrl bench_url;      // [bench] url, parsed
  std::string bench_profile_path;  // absolute
  motion::DriveProfile bench_profile;
  // e.g. "gige:127.0.0.1" (scheme validated); a replay folder is made absolute.
  std::string camera_spec;
  // [capture] as the frame source takes it. capture.retries (the file's
  // capture.retries) is also what the controller allows per position:
  // re-triggers after a camera timeout or an incomplete frame, frames
  // discarded for being stamped before the bench settled, and retakes when
  // the read-back moved during the exposures, before the position fails.
  vision::CaptureOptions capture;
  // [capture] grab_timeout_ms: how long one grab waits for its frame.
  std::chrono::milliseconds grab_timeout{2000};
  std::string camera_calibration_path;  // absolute, or "" = the paper's Sony XC-555
  vision::Camera camera = vision::Camera::paper_default();
  std::string target_layout_path;  // absolute
  vision::Target target;
  // [detect] detectors, in vision::detector_names() order whatever the
  // file's (the measurer's order; the first is the run's primary detector);
  // default every detector that decodes target.family. Never empty: a family
  // no detector reads is refused.
  std::vector<std::string> detectors;
  std::string rig_geometry_path;  // absolute file the geometry came from ("" if inline)
  std::string rig_geometry_text;  // the geometry's TOML (file content, or the inline tables)
  vision::RigGeometry geometry;
  // Folder for raw frames as PNG, absolute; unset = frames are not saved.
  // Saving keeps every frame for re-analysis (up to 0.4 MB per 736x571 Mono8
  // frame) at the cost of disk and an encode per frame.
  std::optional<std::string> frames_dir;
  std::string database_path;  // absolute; `rig sweep --db` overrides
  // [telemetry], validated as telemetry::validate_endpoints does (defaults:
  // the TelemetryEndpoints defaults). allow_remote false: both endpoints must
  // be loopback, so nobody on the network can pause or abort a run; true
  // allows e.g. tcp://*:5556 for a remote monitor.
  telemetry::TelemetryEndpoints telemetry;
  // fsync the database after every position: a power cut loses at most the
  // position being measured; false is faster on slow disks but may lose the
  // last positions (the run then resumes from an earlier one).
  bool durable_commits = true;
  // [compute] threads: threads that measure frames (detector and solvers,
  // whole frames at a time; rig::sweep::FramePool). 1 measures every frame on
  // the controller's thread; more overlap a position's frames with each other
  // and with the capture. Results do not depend on it.
  int compute_threads = default_compute_threads();
  // Not a sweep-file key (replay_config sets it): the controller acquires
  // each position (move, settle, frames) before it finishes and stores the
  // one before, so that consecutive positions' frames are measured in
  // parallel. Only for a bench and a frame source that record nothing while
  // acquiring (a replay's): what is recorded, and its order, stay those of
  // the one-at-a-time path (rig/sweep/controller.hpp).
  bool acquire_ahead = false;
  // [[estimator]]: external estimators run on every frame beside the
  // built-in solvers, in file order (docs/external-estimators.md).
  std::vector<estimator::EstimatorSpec> estimators;

  // The calibration as a message names it: its path, or the built-in paper
  // camera when capture.calibration is "".
  std::string calibration_description() const {
    return camera_calibration_path.empty()
               ? "the built-in paper camera (capture.calibration = \"\")"
               : camera_calibration_path;
  }
  // Every resolved value (absolute paths, defaults filled in, the plan's
  // description and size but not its positions), for runs.config_json.
  nlohmann::json to_json() const;
  // The [[estimator]] specs as to_json() stores them under "estimators".
  nlohmann::json estimators_json() const;
};

// Reads, resolves and validates a sweep file (format above; a regular file of
// at most 1 MiB, config/reader.hpp). Throws SweepConfigError naming the file,
// the key, the value and what was expected.
SweepConfig load_sweep_config(const std::string& path);

}  // namespace rig::sweep
