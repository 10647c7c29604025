// The public JSON form of a pose estimate, shared by `rig solve` and `rig detect`:
// {"solver", "R": [[3],[3],[3]], "t": [x, y, z], "distance_m",
//  "reprojection_error_px", "converged", "iterations", "time_us",
//  "termination", "ambiguity_ratio" (where defined), "message" (where set)},
// or {"solver", "skipped": reason} for a solver that does not apply.
// R and t are T_cam_target (metres).
#pragma once

#include <nlohmann/json.hpp>

#include "vision/pose_solver.hpp"

namespace rig::cli {

nlohmann::json estimate_to_json(const vision::Estimate& e);

}  // namespace rig::cli
