// The JSON form of a pose, shared by what a run stores and what rig prints:
// the rig geometry in a run's configuration (runs.config_json, T_carriage_cam
// and T_bench_target, docs/database.md) and the estimates of `rig solve` and
// `rig detect` (T_cam_target). Frames: docs/frames.md.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "vision/pose.hpp"

namespace rig::sweep {

// `v` as a JSON number, or null when it is not finite (JSON has no NaN or
// infinity).
nlohmann::json finite_or_null(double v);

// T_a_b (x_a = R x_b + t) as {"R": [[r00, r01, r02], [r10, ...], [r20, ...]],
// translation_key: [x, y, z]}: R row by row, t in metres, each value through
// finite_or_null. translation_key is the name the format gives t: "t_m" in a
// run's configuration, "t" in an estimate.
nlohmann::json pose_to_json(const vision::Pose& T, const std::string& translation_key);

}  // namespace rig::sweep
