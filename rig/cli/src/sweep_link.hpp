// The live link of one `rig sweep`: its telemetry publisher, its control
// socket (status, pause, resume, abort; docs/telemetry.md) and SIGINT/SIGTERM
// as abort requests. Bound before anything else happens, so that a second
// sweep on the same ports stops before it touches the camera, the bench or
// the database.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>

#include "rig/sweep/controller.hpp"
#include "rig/telemetry/telemetry.hpp"

namespace rig::cli {

class SweepLink {
 public:
  // Binds both endpoints (validate_endpoints first) and starts answering the
  // control socket and turning SIGINT/SIGTERM into abort requests. Throws
  // telemetry::TelemetryError naming an endpoint that cannot be bound.
  explicit SweepLink(const telemetry::TelemetryEndpoints& endpoints);
  ~SweepLink();
  SweepLink(const SweepLink&) = delete;
  SweepLink& operator=(const SweepLink&) = delete;

  // While the guard lives, the control socket's `status` describes
  // `controller`; afterwards it repeats the controller's last status (the
  // guard detaches on every path out, exceptions included).
  class Attached {
   public:
    Attached(SweepLink& link, sweep::Controller& controller);
    ~Attached();
    Attached(const Attached&) = delete;
    Attached& operator=(const Attached&) = delete;

   private:
    SweepLink& link_;
  };

  // `status` says {"state": "starting", "run_id": run_id} until a controller
  // is attached.
  void set_run(std::int64_t run_id);
  // The bound control endpoint, e.g. tcp://127.0.0.1:5557.
  std::string control_endpoint() const;

  telemetry::ControlState control;
  telemetry::TelemetryPublisher publisher;

 private:
  class SignalWatch;
  nlohmann::json status();

  std::mutex mutex_;
  sweep::Controller* live_ = nullptr;
  nlohmann::json last_ = {{"state", "starting"}};
  telemetry::ControlServer server_;       // its thread calls status() until it is destroyed
  std::unique_ptr<SignalWatch> signals_;  // SIGINT/SIGTERM from here on: an abort request
};

}  // namespace rig::cli
