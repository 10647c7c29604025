// The truth of a recorded run under another rig geometry and camera
// calibration (rig report --geometry FILE [--calibration FILE]): from each
// position's stored bench read-back, rig::sweep::ground_truth_at gives the
// true distance, viewing angle, markers in view and Cramér-Rao bounds as the
// sweep would have stored them had it run with these files.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "db/report/report.hpp"
#include "db/store/records.hpp"

namespace rig::cli {

struct TruthFiles {
  std::string geometry;                    // a rig geometry file (rig.toml of rig calibrate)
  std::optional<std::string> calibration;  // a camera file; unset: the run's stored calibration
};

// Loads the files (a missing file or a bad key: config::ConfigError or
// vision::CalibrationError naming the file and key, exit 2) and recomputes
// the truth of every position with a read-back; the target layout is the
// run's stored one. Positions without a read-back get no truth.
db::report::RecomputedTruth recompute_truth(
    const TruthFiles& files, const db::store::Run& run,
    const std::vector<db::store::PositionRecord>& positions);

}  // namespace rig::cli
