// vision::seconds_since: the wall time of one stage (detection, a solver, a
// capture, a commit), as the per-stage timings of a measurement and of a
// sweep record it (docs/telemetry.md).
#pragma once

#include <chrono>

namespace vision {

// Seconds elapsed on the steady (monotonic) clock from `start` to now: >= 0,
// unaffected by changes of the system clock. `start` is a
// std::chrono::steady_clock::now() taken earlier.
double seconds_since(std::chrono::steady_clock::time_point start);

}  // namespace vision
