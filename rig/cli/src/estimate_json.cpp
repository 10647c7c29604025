#include "estimate_json.hpp"

#include <cmath>

namespace rig::cli {
namespace {

// JSON has no NaN or infinity; a non-finite number is written as null.
nlohmann::json number(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

}  // namespace

nlohmann::json estimate_to_json(const vision::Estimate& e) {
  if (!e.applicable()) return {{"solver", e.solver}, {"skipped", e.message}};
  nlohmann::json R = nlohmann::json::array();
  for (int r = 0; r < 3; ++r)
    R.push_back({number(e.T_cam_target.R(r, 0)), number(e.T_cam_target.R(r, 1)),
                 number(e.T_cam_target.R(r, 2))});
  nlohmann::json j = {
      {"solver", e.solver},
      {"R", R},
      {"t",
       {number(e.T_cam_target.t.x()), number(e.T_cam_target.t.y()), number(e.T_cam_target.t.z())}},
      {"distance_m", number(e.distance_m)},
      {"reprojection_error_px", number(e.reprojection_error_px)},
      {"converged", e.converged},
      {"iterations", e.iterations},
      {"time_us", number(e.time_us)},
      {"termination", vision::to_string(e.termination)}};
  if (e.ambiguity_ratio) j["ambiguity_ratio"] = number(*e.ambiguity_ratio);
  if (!e.message.empty()) j["message"] = e.message;
  return j;
}

}  // namespace rig::cli
