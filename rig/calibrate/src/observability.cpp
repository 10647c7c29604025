// The plan-extent rule of check_observable (calibration.hpp).
#include <algorithm>
#include <sstream>

#include "rig/calibrate/calibration.hpp"

namespace rig::calibrate {
namespace {

// Below this spread of the read-backs (mm) an axis counts as not moved: well
// above encoder resolution and repeatability, well below any useful step.
constexpr double kMinSpanMm = 1.0;

std::string mm(double v) {
  std::ostringstream s;
  s.precision(3);
  s << v << " mm";
  return s.str();
}

}  // namespace

void check_observable(const CalibrationProblem& problem) {
  if (problem.corners.empty())
    throw CalibrationInputError(problem.source + ": no detected corners to calibrate from");
  double x_min = problem.corners.front().x_mm, x_max = x_min;
  double y_min = problem.corners.front().y_mm, y_max = y_min;
  for (const CornerObservation& o : problem.corners) {
    x_min = std::min(x_min, o.x_mm);
    x_max = std::max(x_max, o.x_mm);
    y_min = std::min(y_min, o.y_mm);
    y_max = std::max(y_max, o.y_mm);
  }
  if (x_max - x_min < kMinSpanMm)
    throw UnobservablePlan(problem.source +
                           ": fx/fy and target distance are not separable: the plan has one "
                           "bench distance (the read-backs span " +
                           mm(x_max - x_min) + " in x; at least " + mm(kMinSpanMm) +
                           " expected, better the whole working range)");
  if (y_max - y_min < kMinSpanMm)
    throw UnobservablePlan(problem.source +
                           ": camera_misalignment_z_deg (the camera's rotation about the bench x "
                           "axis) and target_tilt_z_deg are not separable: the plan has one row "
                           "(the read-backs span " +
                           mm(y_max - y_min) + " in y; at least " + mm(kMinSpanMm) +
                           " expected, better the whole travel)");
}

}  // namespace rig::calibrate
