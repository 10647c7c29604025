// The simulated rig in the test process, for end-to-end sweeps run by the
// real `rig sweep` program: a real Modbus TCP bench server (sim::bench::BenchServer
// on an ephemeral port) and the real GigE Vision camera on loopback
// (sim::camera::CameraServer, rendering what the camera sees at the bench's actual
// position). The test holds both, so it can inject faults while `rig sweep`
// runs as a child process it can signal or kill.
#pragma once

#include <sqlite3.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "child_process.hpp"
#include "motion/drive_profile.hpp"
#include "rig_command.hpp"
#include "sim/bench/config.hpp"
#include "sim/bench/server.hpp"
#include "sim/camera/server.hpp"
#include "vision/codebook.hpp"
#include "vision/rig_geometry.hpp"

namespace rig_test {

inline std::string repo_path(const std::string& relative) {
  return std::string(RIG_SOURCE_DIR) + "/" + relative;
}

inline std::string rig_binary() {
  return std::string(RIG_BINARY_DIR) + "/bin/rig";
}

struct SweepFileOptions {
  std::string plan = "kind = \"grid\"\nx_mm = [300.0, 800.0, 100.0]\ny_mm = [150.0, 150.0, 10.0]\n";
  int frames = 2;
  std::string on_alarm = "abort";
  int max_consecutive_failed = 5;
  std::string calibration;  // "" = the paper camera
  std::string extra_capture;
  std::string extra_faults;  // more [faults] keys, one "key = value\n" each
  // [detect] detectors as TOML ("" = the key left out: every detector that
  // reads the target's family). rig's alone by default: the tests of the
  // sweep's other parts need one detector's rows, and seven detectors cost
  // several times the measurement time per frame.
  std::string detectors = "[\"rig\"]";
  // Telemetry endpoints. Ports chosen at bind time by default, so that no
  // test needs a fixed port to be free; the sweep prints the ports on its
  // first line. Two loopback addresses: the sweep refuses two identical
  // endpoints, even when both ports are chosen at bind time.
  std::string telemetry_publish = "tcp://127.0.0.1:*";
  std::string telemetry_control = "tcp://127.0.0.2:*";
};

class SimRig {
 public:
  // time_scale: simulated seconds per wall second of the bench's motion
  // (the camera still exposes in real time). rtu_device, when given: the bench
  // serves Modbus RTU on that serial device (one end of a socat pty pair)
  // instead of TCP; then set_bench_url names the other end for the sweep file.
  explicit SimRig(double time_scale = 4.0, const std::string& rtu_device = "")
      : dir_(std::filesystem::temp_directory_path() /
             ("rig_sweep_" + std::to_string(::getpid()) + "_" + std::to_string(counter()++))),
        geometry_(vision::RigGeometry::load(repo_path("config/rigs/sim.toml"))) {
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    sim::bench::BenchSimConfig sim_config =
        sim::bench::load_bench_sim_config(repo_path("config/benches/sim.toml"));
    sim_config.time_scale = time_scale;
    sim::bench::BenchServerOptions server;
    server.rtu_device = rtu_device;
    bench_ = std::make_unique<sim::bench::BenchServer>(
        motion::load_drive_profile(repo_path("config/benches/sim.toml")), sim_config, server);
    bench_->start();
    auto renderer = std::make_shared<const sim::scene::SceneRenderer>(
        vision::Camera::paper_default(),
        vision::Target::load(repo_path("config/targets/paper.toml")), vision::Codebook());
    sim::bench::BenchServer* bench = bench_.get();
    camera_ = std::make_unique<sim::camera::CameraServer>(renderer, geometry_, [bench] {
      const motion::XY p = bench->actual_position_mm();
      return std::make_pair(p.x_mm, p.y_mm);
    });
    camera_->start();
  }
  ~SimRig() {
    camera_.reset();
    bench_.reset();
    std::filesystem::remove_all(dir_);
  }

  sim::bench::BenchServer& bench() { return *bench_; }
  // The bench URL write_sweep writes; default: the bench's TCP address.
  void set_bench_url(const std::string& url) { bench_url_ = url; }
  sim::camera::CameraServer& camera() { return *camera_; }
  const vision::RigGeometry& geometry() const { return geometry_; }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  std::string database() const { return file("run.db"); }

  // Writes a sweep file for this rig; returns its path.
  std::string write_sweep(const SweepFileOptions& o, const std::string& name = "sweep.toml") const {
    std::ofstream out(file(name));
    out << "[plan]\n"
        << o.plan << "\n[capture]\ncamera = \"gige:127.0.0.1\"\ncalibration = \"" << o.calibration
        << "\"\nframes_per_position = " << o.frames << "\n"
        << o.extra_capture << "\n[bench]\nurl = \""
        << (bench_url_.empty() ? "modbus-tcp://127.0.0.1:" + std::to_string(bench_->port())
                               : bench_url_)
        << "\"\nprofile = \"" << repo_path("config/benches/sim.toml")
        << "\"\nspeed_mm_s = 100\n\n[faults]\non_alarm = \"" << o.on_alarm
        << "\"\nmax_consecutive_failed = " << o.max_consecutive_failed << "\n"
        << o.extra_faults << "\n[target]\nlayout = \"" << repo_path("config/targets/paper.toml")
        << "\"\n"
        << (o.detectors.empty() ? "" : "\n[detect]\ndetectors = " + o.detectors + "\n")
        << "\n[rig]\nfile = \"" << repo_path("config/rigs/sim.toml")
        << "\"\n\n[database]\npath = \"" << database()
        << "\"\ndurable_commits = true\n\n[telemetry]\npublish = \"" << o.telemetry_publish
        << "\"\ncontrol = \"" << o.telemetry_control << "\"\n";
    return file(name);
  }

 private:
  static int& counter() {
    static int n = 0;
    return n;
  }
  std::filesystem::path dir_;
  std::string bench_url_;
  vision::RigGeometry geometry_;
  std::unique_ptr<sim::bench::BenchServer> bench_;
  std::unique_ptr<sim::camera::CameraServer> camera_;
};

// Read-only SQL on a run database, independent of db::store::Store: what the file
// holds, as another program would see it.
class SqlProbe {
 public:
  explicit SqlProbe(const std::string& path) {
    if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK)
      throw std::runtime_error("cannot open " + path);
  }
  ~SqlProbe() { sqlite3_close(db_); }
  SqlProbe(const SqlProbe&) = delete;
  SqlProbe& operator=(const SqlProbe&) = delete;

  // The first column of every row, as text.
  std::vector<std::string> column(const std::string& sql) const {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &s, nullptr) != SQLITE_OK)
      throw std::runtime_error(sql + ": " + sqlite3_errmsg(db_));
    std::vector<std::string> out;
    while (sqlite3_step(s) == SQLITE_ROW) {
      const auto* t = sqlite3_column_text(s, 0);
      out.push_back(t ? reinterpret_cast<const char*>(t) : "NULL");
    }
    sqlite3_finalize(s);
    return out;
  }
  std::string value(const std::string& sql) const {
    const auto c = column(sql);
    return c.empty() ? "" : c.front();
  }
  long long count(const std::string& sql) const { return std::stoll(value(sql)); }

 private:
  sqlite3* db_ = nullptr;
};

}  // namespace rig_test
