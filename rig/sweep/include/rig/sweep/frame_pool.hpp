// rig::sweep::FramePool: vision::FrameMeasurer::measure (the detector and every
// solver on one frame) on several threads, whole frames at a time, so that the
// frames of a position, or the next position's frames, are measured in
// parallel while the caller keeps everything that must stay in order (logging,
// telemetry, external estimators, the database) on its own thread.
//
// A frame is submitted as soon as it is grabbed and its measurement is taken
// later, in whatever order the caller wants (the controller takes them in
// frame order). Each measurement is exactly what measure() returns on the
// caller's thread: measure() is a const function of the image and of the
// measurer's immutable camera, target, detector and solvers (no shared
// mutable state; tests/rig/sweep/frame_pool_test.cpp holds the results of 1
// and 2 threads equal field by field). Only its detect_s and solve_s wall
// times depend on what else runs meanwhile.
//
// threads = 1 is the serial path: nothing runs in the background; take()
// measures the frame on the caller's thread. threads = N > 1 starts N - 1
// worker threads, and a caller waiting in take() measures queued frames
// itself, oldest first, its own before any submitted after it: so N threads
// measure, and a caller whose frame a worker is measuring measures the next
// one (the next position's, when they were handed over ahead) instead of
// waiting. Its take() then returns when that frame is done: at most one
// frame's measurement later than its own was ready. Frames are started in
// submission order.
//
// While a pool of N > 1 threads lives, OpenCV's own parallel loops are off
// (cv::setNumThreads(1), process-wide; the previous setting comes back when
// the last such pool is destroyed): the frames are the unit of parallelism,
// and OpenCV's worker threads would compete with the pool's for the same
// cores (bench_sweep, two threads and ahead: about 10 % more positions per
// second). The measurements are the same either way: OpenCV's parallel
// loops split an image into stripes that give the same pixels.
#pragma once

#include <condition_variable>
#include <deque>
#include <future>
#include <mutex>
#include <opencv2/core.hpp>
#include <thread>
#include <vector>

#include "vision/frame_measurement.hpp"

namespace rig::sweep {

// The [compute] threads default: the machine's hardware threads, at least 1.
int default_compute_threads();

class FramePool {
 public:
  // A submitted frame's measurement, to be taken once with take().
  struct Ticket {
    std::future<vision::FrameMeasurement> measurement;
  };

  // Measures with `measurer`, which must outlive the pool. Precondition:
  // 1 <= threads <= kMaxThreads (std::invalid_argument otherwise).
  FramePool(const vision::FrameMeasurer& measurer, int threads);
  // Waits for the frames being measured; frames still queued are dropped.
  ~FramePool();
  FramePool(const FramePool&) = delete;
  FramePool& operator=(const FramePool&) = delete;

  static constexpr int kMaxThreads = 256;

  int threads() const { return threads_; }
  const vision::FrameMeasurer& measurer() const { return measurer_; }

  // Queues `image` (shared, not copied: the caller must not write to its
  // pixels until the ticket is taken or dropped) for measurement.
  Ticket submit(cv::Mat image);

  // The measurement of `ticket`, waiting for it; while it waits, the caller
  // measures the frames still queued, oldest first (its own included).
  // Rethrows what measure() threw (e.g. std::invalid_argument for an image
  // type the detector cannot read). Precondition: ticket came from this
  // pool's submit() and was not taken. A ticket that is dropped instead is
  // measured all the same, and the result discarded.
  vision::FrameMeasurement take(Ticket& ticket);

 private:
  void work();
  bool run_one_queued();

  const vision::FrameMeasurer& measurer_;
  const int threads_;
  std::mutex mutex_;
  std::condition_variable queued_;
  std::deque<std::packaged_task<vision::FrameMeasurement()>> queue_;  // in submission order
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace rig::sweep
