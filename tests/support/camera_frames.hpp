// What the tests of a camera (simulated, through the real capture path)
// share: how long a grab may wait and how two frames are compared.
#pragma once

#include <chrono>
#include <opencv2/core.hpp>

namespace rig_test {

// A frame arrives within tens of milliseconds (render and exposure); a grab
// returns as soon as it is there, so this only bounds a broken test, with
// room for a loaded host or a sanitizer build.
constexpr std::chrono::seconds kFrameWait{10};

// How many pixels of `a` and `b` differ; -1 when their sizes or types differ.
inline int differing_pixels(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return -1;
  return cv::countNonZero(a != b);
}

}  // namespace rig_test
