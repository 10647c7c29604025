// motion::SettleWatch: the in-position dwell of wait_settled, fed one poll at
// a time: settled once the bench has been on target at every poll for at
// least the settle time (profile timing.settle_time_ms).
#pragma once

#include <chrono>

namespace motion {

class SettleWatch {
 public:
  explicit SettleWatch(std::chrono::milliseconds settle_time) : settle_time_(settle_time) {}

  // True when `on_target` has held at this poll and every poll since one at
  // least settle_time before `now`; a poll off target starts the dwell over.
  bool settled(bool on_target, std::chrono::steady_clock::time_point now) {
    if (!on_target) {
      on_target_ = false;
      return false;
    }
    if (!on_target_) since_ = now;
    on_target_ = true;
    return now - since_ >= settle_time_;
  }

 private:
  std::chrono::milliseconds settle_time_;
  bool on_target_ = false;  // at the previous poll
  std::chrono::steady_clock::time_point since_{};
};

}  // namespace motion
