#include "telemetry_messages.hpp"

#include <algorithm>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace rig::sweep {

nlohmann::json position_message(const db::store::PositionRecord& rec, const std::string& detector,
                                std::int64_t run_id, std::int64_t stored, std::int64_t plan_size,
                                double elapsed_s) {
  nlohmann::json estimates = nlohmann::json::array();
  // Means over the frames, per solver and scope.
  struct Sum {
    double distance = 0, reprojection = 0, generalization = 0;
    int n = 0, n_generalization = 0;
    bool converged = true;
    bool applicable = false;  // some frame's estimate was not skipped as not applicable
  };
  std::map<std::pair<std::string, std::string>, Sum> sums;
  std::vector<std::pair<std::string, std::string>> order;
  std::size_t markers = 0;
  for (const auto& f : rec.frames) {
    markers = std::max(markers, static_cast<std::size_t>(std::count_if(
                                    f.detections.begin(), f.detections.end(),
                                    [&](const auto& d) { return d.detector == detector; })));
    for (const auto& e : f.estimates) {
      if (e.detector != detector) continue;
      const auto key = std::make_pair(e.solver, e.scope);
      if (!sums.count(key)) order.push_back(key);
      Sum& s = sums[key];
      s.converged = s.converged && e.converged;
      s.applicable |= e.termination != "not_applicable" && e.termination != "skipped";
      if (!e.converged) continue;
      s.distance += e.distance_m;
      s.reprojection += e.reprojection_error_px;
      ++s.n;
      if (e.generalization_error_px) {
        s.generalization += *e.generalization_error_px;
        ++s.n_generalization;
      }
    }
  }
  for (const auto& key : order) {
    const Sum& s = sums[key];
    nlohmann::json j = {{"solver", key.first},
                        {"scope", key.second},
                        {"converged", s.converged},
                        {"applicable", s.applicable}};
    if (s.n > 0) {
      j["distance_m"] = s.distance / s.n;
      j["distance_error_m"] = rec.true_distance_m
                                  ? nlohmann::json(s.distance / s.n - *rec.true_distance_m)
                                  : nlohmann::json(nullptr);
      j["reprojection_error_px"] = s.reprojection / s.n;
    } else {
      j["distance_m"] = j["distance_error_m"] = j["reprojection_error_px"] = nullptr;
    }
    j["generalization_error_px"] = s.n_generalization > 0
                                       ? nlohmann::json(s.generalization / s.n_generalization)
                                       : nlohmann::json(nullptr);
    estimates.push_back(std::move(j));
  }
  nlohmann::json stages = nlohmann::json::object();
  for (const auto& st : rec.stage_times)
    stages[st.stage] = st.seconds;
  auto optional = [](const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
  };
  return {
      {"type", "position"},
      {"run_id", run_id},
      {"plan_index", rec.plan_index},
      {"completed", stored},
      {"plan_size", plan_size},
      {"status", db::store::to_string(rec.status)},
      {"failure_reason", rec.failure_reason},
      {"commanded", {{"x_mm", rec.commanded_x_mm}, {"y_mm", rec.commanded_y_mm}}},
      {"measured", {{"x_mm", optional(rec.measured_x_mm)}, {"y_mm", optional(rec.measured_y_mm)}}},
      {"true_distance_m", optional(rec.true_distance_m)},
      {"markers_detected", markers},
      {"estimates", estimates},
      {"stage_times_s", stages},
      {"elapsed_s", elapsed_s}};
}

}  // namespace rig::sweep
