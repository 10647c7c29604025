// A simulated bench server on an ephemeral loopback port, with the shipped
// profile config/benches/sim.toml, for tests of the driver and the server.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "motion/drive_profile.hpp"
#include "motion/modbus_bench.hpp"
#include "sim/bench/config.hpp"
#include "sim/bench/server.hpp"

namespace rig_test {

inline std::string sim_profile_path() {
  return std::string(RIG_SOURCE_DIR) + "/config/benches/sim.toml";
}

// The shipped map with test timings. A loopback transaction takes
// microseconds, so with a 1 s response timeout only a fault injected on
// purpose times out, never a reply the loaded host or a sanitizer build was
// slow to send (a spurious timeout would add a reconnect, and repeat a write
// whose fault the server had already spent). A 1.5 s reconnect window keeps
// the link-fault tests short.
inline motion::DriveProfile test_profile() {
  motion::DriveProfile p = motion::load_drive_profile(sim_profile_path());
  p.timing.response_timeout_ms = 1000;
  p.timing.reconnect_timeout_ms = 1500;
  return p;
}

// The shipped physics at time scale 10 (ten simulated seconds per wall
// second), without repeatability noise unless a test asks for it.
inline sim::bench::BenchSimConfig test_sim_config() {
  sim::bench::BenchSimConfig c = sim::bench::load_bench_sim_config(sim_profile_path());
  c.time_scale = 10;
  c.x.repeatability_mm = c.y.repeatability_mm = 0;
  return c;
}

class SimBenchTest : public ::testing::Test {
 protected:
  // Starts the server; call from the test body after adjusting profile_ and sim_.
  void start_server() {
    server_ = std::make_unique<sim::bench::BenchServer>(profile_, sim_, options_);
    server_->start();
  }
  std::unique_ptr<motion::ModbusBench> connect() {
    return std::make_unique<motion::ModbusBench>(motion::BenchUrl::parse(server_->url()), profile_);
  }
  // Server started, bench connected and homed.
  std::unique_ptr<motion::ModbusBench> homed_bench() {
    if (!server_) start_server();
    auto bench = connect();
    bench->home();
    bench->wait_settled(std::chrono::seconds(5));
    return bench;
  }

  motion::DriveProfile profile_ = test_profile();
  sim::bench::BenchSimConfig sim_ = test_sim_config();
  sim::bench::BenchServerOptions options_;
  std::unique_ptr<sim::bench::BenchServer> server_;
};

}  // namespace rig_test
