// What a run database holds about a sweep besides its positions (docs/database.md):
// the run's description (the sweep file and every file it names as stored
// copies with their SHA-256, the resolved configuration, the plan, software
// and library versions, host), and the checks a resume makes against it.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

#include "db/store/records.hpp"
#include "db/store/store.hpp"
#include "rig/sweep/sweep_config.hpp"
#include "rig/sweep/sweep_plan.hpp"

namespace rig::sweep {

// A resume or replay that cannot go on: the message names the run, the file
// and what differs.
class RunMismatch : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The run's description. Reads the files the config names (the calibration
// may be "" = the built-in paper camera, stored as an empty file). Throws
// SweepConfigError if a file cannot be read.
db::store::RunDescription describe_run(
    const SweepConfig& config, const SweepPlan& plan,
    const nlohmann::json& extra_config = nlohmann::json::object());

// {"opencv": "4.6.0", "aravis": ..., "libmodbus": ..., "sqlite": ..., "zeromq": ..., "eigen": ...}
nlohmann::json library_versions();

// A JSON text a run database stores (a run's configuration or plan), parsed
// within config::JsonLimits (config/json.hpp): a text that is not JSON, or is
// too big or too deeply nested for one rig wrote, gives a discarded value
// (is_discarded()), so a damaged or crafted database cannot crash a reader.
nlohmann::json parse_stored_json(const std::string& text);

// For `rig sweep --resume RUN`: the run's stored plan, after checking that
// every file the config read has the SHA-256 the run stored (a resumed run
// must measure with what it started with). Throws RunMismatch naming the
// file that changed, or the run's status if it is completed (unless
// completed_allowed: `--retry-failed` on a run with failed positions); PlanError if the
// stored plan is damaged; SweepConfigError if a file cannot be read.
SweepPlan plan_for_resume(const db::store::Run& run, const SweepConfig& config,
                          bool completed_allowed = false);

}  // namespace rig::sweep
