// motion::DrivenBench: a Bench driven through a drive profile, with the
// controls a person or a sweep sets beyond the Bench interface (speed), and
// open_bench, which builds the right one for a profile: a ModbusBench for one
// controller of both axes, a TwoDriveBench for two single-axis drives
// (docs/drive-profile.md#two-single-axis-drives-as-one-xy-bench).
#pragma once

#include <memory>

#include "motion/bench.hpp"
#include "motion/bench_url.hpp"
#include "motion/drive_profile.hpp"

namespace motion {

class DrivenBench : public Bench {
 public:
  // Speed written with every following move, mm/s (each axis at this speed).
  // Throws SoftLimitError if not in (0, profile().max_speed_mm_s] (NaN
  // included) or if it rounds to 0 in a drive's units.
  virtual void set_speed(double speed_mm_s) = 0;
  // The bench's profile: for two drives, the shared [motion] and
  // [soft_limits] and, in axis_drives, each drive's.
  virtual const DriveProfile& profile() const = 0;
  // How many times a reconnect watchdog re-established a link (for logs, tests).
  virtual int reconnects() const = 0;
};

// Connects to the bench `profile` describes at `url`. For two single-axis
// drives, a drive with a `url` of its own is reached there, the other at
// `url` with its own link.unit_id; `url` must then not name a unit (?unit=),
// which would be one unit for two drives (ProfileError). Throws what the
// constructors throw (BenchLinkError when a drive cannot be reached).
std::unique_ptr<DrivenBench> open_bench(const BenchUrl& url, const DriveProfile& profile);

}  // namespace motion
