// The telemetry message of a stored position (rig/telemetry/telemetry.hpp
// lists the message types): bench XY, true distance, each solver's distance
// and errors as means over the position's frames, stage times.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "db/store/records.hpp"

namespace rig::sweep {

// The markers and estimates of the run's primary detector `detector` only;
// stored: positions the run has, this one included; elapsed_s: seconds since
// this session of the run started.
nlohmann::json position_message(const db::store::PositionRecord& position,
                                const std::string& detector, std::int64_t run_id,
                                std::int64_t stored, std::int64_t plan_size, double elapsed_s);

}  // namespace rig::sweep
