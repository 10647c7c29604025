#include "rig/sweep/frame_pool.hpp"

#include <algorithm>
#include <chrono>
#include <mutex>
#include <opencv2/core/utility.hpp>
#include <stdexcept>
#include <string>
#include <utility>

namespace rig::sweep {
namespace {

// How many pools of more than one thread live, and OpenCV's thread count
// before the first of them turned its parallel loops off.
std::mutex opencv_threads_mutex;
int opencv_serial_holders = 0;
int opencv_threads_before = 0;

void hold_opencv_serial() {
  const std::lock_guard<std::mutex> lock(opencv_threads_mutex);
  if (opencv_serial_holders++ == 0) {
    opencv_threads_before = cv::getNumThreads();
    cv::setNumThreads(1);
  }
}

void release_opencv_serial() {
  const std::lock_guard<std::mutex> lock(opencv_threads_mutex);
  if (--opencv_serial_holders == 0) cv::setNumThreads(opencv_threads_before);
}

}  // namespace

int default_compute_threads() {
  const unsigned hardware = std::thread::hardware_concurrency();  // 0 when unknown
  return static_cast<int>(std::clamp<unsigned>(hardware, 1, FramePool::kMaxThreads));
}

FramePool::FramePool(const vision::FrameMeasurer& measurer, int threads)
    : measurer_(measurer), threads_(threads) {
  if (threads < 1 || threads > kMaxThreads)
    throw std::invalid_argument("FramePool: threads = " + std::to_string(threads) +
                                "; expected 1.." + std::to_string(kMaxThreads));
  if (threads > 1) hold_opencv_serial();
  for (int k = 1; k < threads; ++k)
    workers_.emplace_back([this] { work(); });
}

FramePool::~FramePool() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    queue_.clear();  // their tickets report std::future_error (broken promise)
  }
  queued_.notify_all();
  for (std::thread& w : workers_)
    w.join();
  if (threads_ > 1) release_opencv_serial();
}

FramePool::Ticket FramePool::submit(cv::Mat image) {
  std::packaged_task<vision::FrameMeasurement()> task(
      [this, image = std::move(image)] { return measurer_.measure(image); });
  Ticket ticket{task.get_future()};
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(task));
  }
  queued_.notify_one();
  return ticket;
}

vision::FrameMeasurement FramePool::take(Ticket& ticket) {
  // The oldest queued frame first: with one thread that is the serial order,
  // and the ticket's own frame comes before any submitted after it.
  std::future<vision::FrameMeasurement>& m = ticket.measurement;
  while (m.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
    if (!run_one_queued()) {
      m.wait();
      break;
    }
  }
  return m.get();
}

bool FramePool::run_one_queued() {
  std::packaged_task<vision::FrameMeasurement()> task;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.empty()) return false;
    task = std::move(queue_.front());
    queue_.pop_front();
  }
  task();  // an exception is stored in the ticket
  return true;
}

void FramePool::work() {
  for (;;) {
    std::packaged_task<vision::FrameMeasurement()> task;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      queued_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      task = std::move(queue_.front());
      queue_.pop_front();
    }
    task();
  }
}

}  // namespace rig::sweep
