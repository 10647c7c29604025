#include "sweep_link.hpp"

#include <atomic>
#include <chrono>
#include <csignal>
#include <string>
#include <thread>

namespace rig::cli {
namespace {

// SIGINT/SIGTERM: finish the current position, then end the run aborted.
std::atomic<int> g_signal{0};
extern "C" void on_stop_signal(int signal) {
  g_signal.store(signal);
}

}  // namespace

// Turns SIGINT/SIGTERM into abort requests of `control` while it lives; the
// previous handlers are restored afterwards.
class SweepLink::SignalWatch {
 public:
  explicit SignalWatch(telemetry::ControlState& control) : control_(control) {
    struct sigaction action {};
    action.sa_handler = on_stop_signal;
    sigemptyset(&action.sa_mask);
    // A system call the signal lands in (a Modbus read, a camera wait) is
    // restarted instead of failing with EINTR as a link or capture fault.
    action.sa_flags = SA_RESTART;
    sigaction(SIGINT, &action, &old_int_);
    sigaction(SIGTERM, &action, &old_term_);
    thread_ = std::thread([this] {
      while (!done_.load()) {
        if (const int s = g_signal.exchange(0)) {
          control_.request_abort(std::string(s == SIGINT ? "SIGINT" : "SIGTERM") + " received");
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    });
  }
  ~SignalWatch() {
    done_.store(true);
    thread_.join();
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  SignalWatch(const SignalWatch&) = delete;
  SignalWatch& operator=(const SignalWatch&) = delete;

 private:
  telemetry::ControlState& control_;
  std::atomic<bool> done_{false};
  std::thread thread_;
  struct sigaction old_int_ {
  }, old_term_{};
};

SweepLink::SweepLink(const telemetry::TelemetryEndpoints& endpoints) try
    : publisher(endpoints.publish),
      server_(endpoints.control, control, [this] { return status(); }),
      signals_(std::make_unique<SignalWatch>(control)) {
} catch (const telemetry::EndpointError&) {
  throw;
} catch (const telemetry::TelemetryError& e) {
  // Both messages name their endpoint; the two endpoints differ.
  const std::string what = e.what();
  const bool control_failed = what.find("\"" + endpoints.control + "\"") != std::string::npos;
  const std::string key = control_failed ? "control" : "publish";
  throw telemetry::TelemetryError(
      what + " (the sweep file's [telemetry] " + key + " = \"" +
      (control_failed ? endpoints.control : endpoints.publish) +
      "\"). Another rig sweep may be running on these ports: `rig ctl status --endpoint " +
      endpoints.control +
      "` asks it. Wait for it or stop it, or give this sweep other ports in its [telemetry] "
      "table");
}

SweepLink::~SweepLink() = default;

SweepLink::Attached::Attached(SweepLink& link, sweep::Controller& controller) : link_(link) {
  std::lock_guard<std::mutex> lock(link_.mutex_);
  link_.live_ = &controller;
}

SweepLink::Attached::~Attached() {
  std::lock_guard<std::mutex> lock(link_.mutex_);
  link_.last_ = link_.live_->status();
  link_.live_ = nullptr;
}

void SweepLink::set_run(std::int64_t run_id) {
  std::lock_guard<std::mutex> lock(mutex_);
  last_ = {{"state", "starting"}, {"run_id", run_id}};
}

std::string SweepLink::control_endpoint() const {
  return server_.endpoint();
}

nlohmann::json SweepLink::status() {
  std::lock_guard<std::mutex> lock(mutex_);
  return live_ ? live_->status() : last_;
}

}  // namespace rig::cli
