#include "estimate_json.hpp"

#include "rig/sweep/pose_json.hpp"

namespace rig::cli {

nlohmann::json estimate_to_json(const vision::Estimate& e) {
  using sweep::finite_or_null;
  if (!e.applicable()) return {{"solver", e.solver}, {"skipped", e.message}};
  nlohmann::json j = sweep::pose_to_json(e.T_cam_target, "t");
  j.update({{"solver", e.solver},
            {"distance_m", finite_or_null(e.distance_m)},
            {"reprojection_error_px", finite_or_null(e.reprojection_error_px)},
            {"converged", e.converged},
            {"iterations", e.iterations},
            {"time_us", finite_or_null(e.time_us)},
            {"termination", vision::to_string(e.termination)}});
  if (e.ambiguity_ratio) j["ambiguity_ratio"] = finite_or_null(*e.ambiguity_ratio);
  if (!e.message.empty()) j["message"] = e.message;
  return j;
}

}  // namespace rig::cli
