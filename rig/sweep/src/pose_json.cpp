#include "rig/sweep/pose_json.hpp"

#include <cmath>

namespace rig::sweep {

nlohmann::json finite_or_null(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

nlohmann::json pose_to_json(const vision::Pose& T, const std::string& translation_key) {
  nlohmann::json R = nlohmann::json::array();
  for (int r = 0; r < 3; ++r)
    R.push_back({finite_or_null(T.R(r, 0)), finite_or_null(T.R(r, 1)), finite_or_null(T.R(r, 2))});
  return {{"R", R},
          {translation_key,
           {finite_or_null(T.t.x()), finite_or_null(T.t.y()), finite_or_null(T.t.z())}}};
}

}  // namespace rig::sweep
