// The corners of one detected marker as observations (calibration.hpp),
// shared by the run's stored detections and by detection again.
#pragma once

#include <array>
#include <vector>

#include "rig/calibrate/calibration.hpp"

namespace rig::calibrate::detail {

// Appends the four corners A..D of layout marker `marker_id` seen at
// `corners_px` (distorted pixels) at plan position `plan_index` with bench
// read-back (x_mm, y_mm); corners that are not finite are left out.
// Precondition: target.has_marker(marker_id).
void append_corners(const vision::Target& target, std::int64_t plan_index, double x_mm, double y_mm,
                    int marker_id, const std::array<Eigen::Vector2d, 4>& corners_px,
                    std::vector<CornerObservation>* out);

}  // namespace rig::calibrate::detail
