// sim::bench::BenchServer: the simulated XY bench as a real Modbus server (libmodbus)
// serving a drive profile's register map, by default rig's own map
// (docs/register-map.md) from config/benches/sim.toml. Over TCP on loopback it serves several
// clients at once; it can also serve one RTU serial line (e.g. one end of a socat pty pair). Any
// Modbus client (ModbusBench, mbpoll, a PLC) can drive it.
//
// Threads: one network thread (a select() loop over the listening socket and
// the clients, woken by a pipe, so stop() returns promptly) and one physics
// thread (advances BenchDynamics every millisecond of wall time, times
// time_scale). The accessors (positions, written_targets, requests) and the
// fault controls (inject, set_emergency_stop) are thread-safe and may be
// called from any thread at any time; start, stop and restart_network belong
// to the one thread that owns the server.
//
// For the simulated camera: actual_position_mm() is where the carriage really
// is, including the backlash and repeatability error the drive never reports;
// render frames from it. Drivers see only the encoder read-back.
//
//   sim::bench::BenchServer bench(motion::load_drive_profile(f),
//   sim::bench::load_bench_sim_config(f), {}); bench.start();                       // listening on
//   127.0.0.1:bench.port() motion::XY p = bench.actual_position_mm();   // from any thread, any
//   time
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "motion/bench.hpp"
#include "motion/drive_profile.hpp"
#include "sim/bench/config.hpp"
#include "sim/bench/dynamics.hpp"

typedef struct _modbus modbus_t;
typedef struct _modbus_mapping_t modbus_mapping_t;

namespace sim::bench {

struct BenchServerOptions {
  std::string host = "127.0.0.1";  // TCP address to listen on
  int port = 0;                    // 0: an ephemeral port, see port()
  std::string rtu_device;          // non-empty: serve this serial device instead of TCP
  int rtu_baud = 115200;
  int max_clients = 16;  // TCP clients served at once; more are refused
};

class BenchServer {
 public:
  // Validates nothing beyond what the config loaders did; starts nothing.
  BenchServer(motion::DriveProfile profile, BenchSimConfig config, BenchServerOptions options = {});
  ~BenchServer();  // stop()
  BenchServer(const BenchServer&) = delete;
  BenchServer& operator=(const BenchServer&) = delete;

  // Starts the physics and network threads. Throws std::runtime_error if the
  // port cannot be bound or the serial device opened.
  void start();
  // Stops both threads and closes every connection (idempotent).
  void stop();
  // Closes the listener and every connection, keeps the drive moving, and
  // listens again on the same port after `downtime` (a gateway reboot).
  // Blocks for `downtime`.
  void restart_network(std::chrono::milliseconds downtime);
  // The drive restarts (a power cycle): the network goes away as in
  // restart_network, and the drive comes back standing, not homed, without an
  // alarm (BenchDynamics::power_cycle). Blocks for `downtime`.
  void power_cycle(std::chrono::milliseconds downtime);

  // TCP port actually listened on (after start()).
  int port() const { return port_; }
  std::string url() const;  // modbus-tcp://HOST:PORT or modbus-rtu://DEVICE?...

  // Where the carriage really is, mm (with backlash and repeatability error).
  motion::XY actual_position_mm() const;
  // What the encoder reads, mm (quantized): the value served to clients.
  motion::XY encoder_position_mm() const;
  // Every write that touched the target registers, decoded, mm; an axis
  // whose registers the write did not touch is empty.
  struct WrittenTarget {
    std::optional<double> x_mm, y_mm;
  };
  std::vector<WrittenTarget> written_targets() const;
  std::uint64_t requests() const;

  // Replaces the fault plan; its counters start now.
  void inject(const FaultPlan& faults);
  void set_emergency_stop(bool on);

 private:
  void physics_loop();
  void network_loop();
  void start_network();
  void stop_network();
  // Returns false when the connection must be closed.
  bool handle(const std::uint8_t* query, int length);
  void refresh_feedback();
  void apply_write(int first, int count);
  bool wait_wall(std::chrono::microseconds d);  // false if stopping

  motion::DriveProfile profile_;
  BenchSimConfig config_;
  BenchServerOptions options_;
  int port_ = 0;

  mutable std::mutex mutex_;  // guards dynamics_, faults_, counters, written_
  BenchDynamics dynamics_;
  FaultPlan faults_;
  std::uint64_t requests_ = 0;
  std::vector<WrittenTarget> written_;

  // Network thread only.
  modbus_t* ctx_ = nullptr;
  modbus_mapping_t* mapping_ = nullptr;
  int listen_fd_ = -1;
  int wake_[2] = {-1, -1};
  std::chrono::steady_clock::time_point stall_until_{};
  std::thread network_;
  bool network_stop_ = false;  // guarded by mutex_

  std::thread physics_;
  std::condition_variable physics_cv_;
  bool physics_stop_ = false;  // guarded by mutex_
};

}  // namespace sim::bench
