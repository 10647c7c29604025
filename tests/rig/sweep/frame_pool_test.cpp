// rig::sweep::FramePool and the controller's parallel paths: frames measured
// on several threads, and positions acquired ahead, give exactly what the
// serial path gives, in the same order. Frames are rendered by the simulated
// rig's renderer (seeded) so that every solver has real corners to work on.
//
// Exact equality, no tolerance: the same code on the same pixels in IEEE
// arithmetic gives the same bits on any thread; a difference could only come
// from state shared between threads, which is what these tests look for.
#include "rig/sweep/frame_pool.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <opencv2/core/utility.hpp>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "db/store/store.hpp"
#include "motion/errors.hpp"
#include "rig/sweep/controller.hpp"
#include "rig/sweep/run_record.hpp"
#include "rig/sweep/sweep_config.hpp"
#include "sim/scene/renderer.hpp"
#include "vision/codebook.hpp"

namespace {

const std::string kSmoke = std::string(RIG_SOURCE_DIR) + "/config/sweeps/smoke.toml";

// The pixels the camera of `config` sees from bench position (x, y), mm.
cv::Mat render_at(const sim::scene::SceneRenderer& renderer, const rig::sweep::SweepConfig& config,
                  double x_mm, double y_mm, std::uint64_t seed) {
  return renderer.render(config.geometry.T_cam_target(x_mm, y_mm), seed).image;
}

void expect_same(const vision::DetectorMeasurement& a, const vision::DetectorMeasurement& b) {
  SCOPED_TRACE(a.detector);
  EXPECT_EQ(a.detector, b.detector);
  ASSERT_EQ(a.detections.size(), b.detections.size());
  for (std::size_t i = 0; i < a.detections.size(); ++i) {
    EXPECT_EQ(a.detections[i].id, b.detections[i].id);
    for (int k = 0; k < 4; ++k)
      EXPECT_EQ(a.detections[i].corners_px[k], b.detections[i].corners_px[k]);
    EXPECT_EQ(a.detections[i].quality.edge_fit_residual_px,
              b.detections[i].quality.edge_fit_residual_px);
  }
  ASSERT_EQ(a.estimates.size(), b.estimates.size());
  for (std::size_t i = 0; i < a.estimates.size(); ++i) {
    const vision::Estimate& ea = a.estimates[i].estimate;
    const vision::Estimate& eb = b.estimates[i].estimate;
    EXPECT_EQ(a.estimates[i].scope, b.estimates[i].scope);
    EXPECT_EQ(ea.solver, eb.solver);
    EXPECT_EQ(ea.T_cam_target.R, eb.T_cam_target.R) << ea.solver;
    EXPECT_EQ(ea.T_cam_target.t, eb.T_cam_target.t) << ea.solver;
    EXPECT_EQ(ea.reprojection_error_px, eb.reprojection_error_px) << ea.solver;
    EXPECT_EQ(ea.iterations, eb.iterations) << ea.solver;
    EXPECT_EQ(ea.converged, eb.converged) << ea.solver;
    EXPECT_EQ(a.estimates[i].generalization_error_px, b.estimates[i].generalization_error_px);
  }
  EXPECT_EQ(a.scope_errors.size(), b.scope_errors.size());
}

// Every detector's measurement the same, in the same order.
void expect_same(const vision::FrameMeasurement& a, const vision::FrameMeasurement& b,
                 const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_EQ(a.detectors.size(), b.detectors.size());
  for (std::size_t d = 0; d < a.detectors.size(); ++d)
    expect_same(a.detectors[d], b.detectors[d]);
}

TEST(FramePool, TwoThreadsMeasureEveryFrameExactlyAsTheCallersThreadDoes) {
  const rig::sweep::SweepConfig config = rig::sweep::load_sweep_config(kSmoke);
  const sim::scene::SceneRenderer renderer(config.camera, config.target, vision::Codebook());
  // Three kinds of detector (rig's, cv::aruco's, libapriltag's with its
  // pooled per-call state) measured on two threads at once.
  const vision::FrameMeasurer measurer(config.camera, config.target, {},
                                       {"rig", "aruco:subpix", "apriltag:d2"});
  std::vector<cv::Mat> frames;
  // Measured serially before the pool exists, with OpenCV's own parallel
  // loops as the process has them; the pool turns them off.
  std::vector<vision::FrameMeasurement> serials;
  for (int k = 0; k < 6; ++k) {
    frames.push_back(render_at(renderer, config, 100.0 * k, 150.0, 40 + k));
    serials.push_back(measurer.measure(frames.back()));
  }
  rig::sweep::FramePool pool(measurer, 2);
  std::vector<rig::sweep::FramePool::Ticket> tickets;
  for (const cv::Mat& f : frames)
    tickets.push_back(pool.submit(f));
  // Taken last first: each ticket holds its own frame's measurement.
  for (std::size_t k = frames.size(); k-- > 0;) {
    const vision::FrameMeasurement parallel = pool.take(tickets[k]);
    const vision::FrameMeasurement& serial = serials[k];
    ASSERT_EQ(serial.detectors.size(), 3u);
    for (const auto& d : serial.detectors)  // config/rigs/sim.toml: the whole sheet in view
      EXPECT_EQ(d.detections.size(), 4u) << d.detector;
    expect_same(serial, parallel, "frame " + std::to_string(k));
  }
}

// The frames are the unit of parallelism: while a pool of more than one
// thread lives OpenCV runs its loops on the calling thread, and the setting
// the process had comes back after the last such pool.
TEST(FramePool, OpenCvRunsSeriallyWhileAPoolOfThreadsLivesAndAsBeforeAfter) {
  const rig::sweep::SweepConfig config = rig::sweep::load_sweep_config(kSmoke);
  const vision::FrameMeasurer measurer(config.camera, config.target);
  const int before = cv::getNumThreads();
  cv::setNumThreads(3);  // not 1, so that turning the loops off shows
  {
    const rig::sweep::FramePool serial(measurer, 1);
    EXPECT_EQ(cv::getNumThreads(), 3) << "the serial path leaves OpenCV as it is";
    auto first = std::make_unique<rig::sweep::FramePool>(measurer, 2);
    EXPECT_EQ(cv::getNumThreads(), 1);
    {
      const rig::sweep::FramePool second(measurer, 2);
      EXPECT_EQ(cv::getNumThreads(), 1);
      first.reset();
      EXPECT_EQ(cv::getNumThreads(), 1) << "a pool of threads still lives";
    }
    EXPECT_EQ(cv::getNumThreads(), 3);
  }
  cv::setNumThreads(before);
}

TEST(FramePool, WhatMeasureThrowsReachesTheTakerAndTheOtherFramesAreMeasured) {
  const rig::sweep::SweepConfig config = rig::sweep::load_sweep_config(kSmoke);
  const vision::FrameMeasurer measurer(config.camera, config.target);
  for (int threads : {1, 2}) {
    rig::sweep::FramePool pool(measurer, threads);
    rig::sweep::FramePool::Ticket bad = pool.submit(cv::Mat(64, 64, CV_8UC2, cv::Scalar(0, 0)));
    rig::sweep::FramePool::Ticket grey = pool.submit(cv::Mat(571, 736, CV_8UC1, cv::Scalar(128)));
    EXPECT_THROW(pool.take(bad), std::invalid_argument) << threads << " threads";
    EXPECT_TRUE(pool.take(grey).primary().detections.empty()) << threads << " threads";
  }
  EXPECT_THROW(rig::sweep::FramePool(measurer, 0), std::invalid_argument);
  EXPECT_THROW(rig::sweep::FramePool(measurer, rig::sweep::FramePool::kMaxThreads + 1),
               std::invalid_argument);
}

// A bench that goes where it is told at once; the position with plan index
// `fail_settle_at` times out settling.
class InstantBench : public motion::Bench {
 public:
  motion::XY at;
  int moves = 0;
  int fail_settle_at = -1;

  void home() override {}
  void move_to(double x_mm, double y_mm) override {
    at = {x_mm, y_mm};
    ++moves;
  }
  motion::BenchStatus wait_settled(std::chrono::milliseconds) override {
    if (moves - 1 == fail_settle_at) throw motion::BenchTimeout("scripted settle timeout");
    return status();
  }
  motion::XY position() override { return at; }
  motion::BenchStatus status() override {
    motion::BenchStatus s;
    s.position = at;
    s.homed = s.in_position = true;
    return s;
  }
  void stop() override {}
  void reset_alarm() override {}
};

// A camera that renders what it sees from the bench's position, frame n with
// seed n (so two sweeps of the same plan see the same pixels).
class RenderingCamera : public vision::FrameSource {
 public:
  RenderingCamera(const rig::sweep::SweepConfig& config, const InstantBench& bench)
      : config_(config),
        bench_(bench),
        renderer_(config.camera, config.target, vision::Codebook()) {}
  void open() override {}
  void trigger() override {}
  vision::Frame grab(std::chrono::milliseconds) override {
    // Rendered once for all the sweeps of a test binary: they grab the same
    // frames in the same order.
    static std::map<std::tuple<double, double, std::uint64_t>, cv::Mat> rendered;
    const auto key = std::make_tuple(bench_.at.x_mm, bench_.at.y_mm, seed_++);
    auto it = rendered.find(key);
    if (it == rendered.end())
      it = rendered
               .emplace(key, render_at(renderer_, config_, bench_.at.x_mm, bench_.at.y_mm,
                                       std::get<2>(key)))
               .first;
    vision::Frame f;
    f.image = it->second;
    f.host_time = std::chrono::system_clock::now();
    return f;
  }
  void close() override {}
  std::string name() const override { return "rendering"; }
  vision::CaptureCounters counters() const override { return {}; }

 private:
  const rig::sweep::SweepConfig& config_;
  const InstantBench& bench_;
  const sim::scene::SceneRenderer renderer_;
  std::uint64_t seed_ = 1;
};

// Every row a run stored that does not depend on when or how fast it ran,
// in the order stored (row ids), one string per row, doubles by their bits.
std::vector<std::string> stored_rows(const std::string& database, std::int64_t run) {
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open_v2(database.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  const std::string r = std::to_string(run);
  const std::string frame = "FROM positions p JOIN frames f ON f.position_id = p.id ";
  const std::vector<std::pair<std::string, std::string>> queries = {
      {"positions",
       "SELECT plan_index, commanded_x_mm, commanded_y_mm, measured_x_mm, measured_y_mm, "
       "true_distance_m, true_viewing_angle_deg, status, failure_reason FROM positions "
       "WHERE run_id = " +
           r + " ORDER BY id"},
      {"stages",
       "SELECT p.plan_index, s.seq, s.stage FROM positions p JOIN stage_times s ON "
       "s.position_id = p.id WHERE p.run_id = " +
           r + " ORDER BY p.id, s.seq"},
      {"frames", "SELECT p.plan_index, f.frame_index, f.source " + frame + "WHERE p.run_id = " + r +
                     " ORDER BY f.id"},
      {"detections",
       "SELECT p.plan_index, f.frame_index, d.marker_id, d.rotation, d.a_x_px, d.a_y_px, d.b_x_px, "
       "d.b_y_px, d.c_x_px, d.c_y_px, d.d_x_px, d.d_y_px, d.contrast, d.bits_corrected, "
       "d.edge_fit_residual_px " +
           frame +
           "JOIN detections d ON d.frame_id = f.id "
           "WHERE p.run_id = " +
           r + " ORDER BY d.id"},
      {"estimates",
       "SELECT p.plan_index, f.frame_index, e.solver, e.scope, e.r00, e.r01, e.r02, e.r10, e.r11, "
       "e.r12, e.r20, e.r21, e.r22, e.tx_m, e.ty_m, e.tz_m, e.distance_m, "
       "e.reprojection_error_px, e.generalization_error_px, e.iterations, e.converged, "
       "e.termination, e.ambiguity_ratio " +
           frame +
           "JOIN estimates e ON e.frame_id = f.id "
           "WHERE p.run_id = " +
           r + " ORDER BY e.id"},
      {"events",
       "SELECT plan_index, kind, message FROM run_events WHERE run_id = " + r + " ORDER BY id"}};
  std::vector<std::string> rows;
  for (const auto& [table, q] : queries) {
    sqlite3_stmt* st = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db, q.c_str(), -1, &st, nullptr), SQLITE_OK) << q;
    while (sqlite3_step(st) == SQLITE_ROW) {
      std::string row = table + ":";
      for (int c = 0; c < sqlite3_column_count(st); ++c) {
        if (sqlite3_column_type(st, c) == SQLITE_FLOAT) {
          char bits[32];
          std::snprintf(bits, sizeof bits, "%a", sqlite3_column_double(st, c));
          row += std::string(" ") + bits;
        } else {
          const unsigned char* text = sqlite3_column_text(st, c);
          row += " " + (text ? std::string(reinterpret_cast<const char*>(text)) : "NULL");
        }
      }
      rows.push_back(row);
    }
    sqlite3_finalize(st);
  }
  sqlite3_close(db);
  return rows;
}

class ParallelSweep : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("rig_frame_pool_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    store_ = std::make_unique<db::store::Store>((dir_ / "run.db").string());
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // A sweep of config/sweeps/smoke.toml (12 positions, 2 frames) with
  // `threads` and `ahead`, position `fail_at` timing out; returns its run.
  std::int64_t sweep(int threads, bool ahead, int fail_at) {
    rig::sweep::SweepConfig config = rig::sweep::load_sweep_config(kSmoke);
    config.compute_threads = threads;
    config.acquire_ahead = ahead;
    InstantBench bench;
    bench.fail_settle_at = fail_at;
    RenderingCamera camera(config, bench);
    rig::telemetry::ControlState control;
    const std::int64_t run = store_->start_run(rig::sweep::describe_run(config, config.plan));
    rig::sweep::Controller controller(config, config.plan, bench, camera, *store_, run, control,
                                      nullptr);
    const rig::sweep::RunOutcome outcome = controller.run();
    EXPECT_EQ(outcome.status, db::store::RunStatus::kCompleted);
    EXPECT_EQ(outcome.positions_failed, 1);
    return run;
  }

  std::filesystem::path dir_;
  std::unique_ptr<db::store::Store> store_;
};

TEST_F(ParallelSweep, FramesInParallelAndPositionsAheadStoreTheSerialRowsInTheSerialOrder) {
  constexpr int kFailAt = 5;  // a failed position between ok ones: its event keeps its place
  const std::vector<std::string> serial = stored_rows(store_->path(), sweep(1, false, kFailAt));
  const std::vector<std::string> parallel = stored_rows(store_->path(), sweep(2, false, kFailAt));
  const std::vector<std::string> ahead = stored_rows(store_->path(), sweep(2, true, kFailAt));
  // 11 ok positions x 2 frames x 4 markers in view, every solver on both scopes.
  std::size_t estimates = 0;
  for (const std::string& row : serial)
    estimates += row.rfind("estimates:", 0) == 0;
  EXPECT_GE(estimates, 11u * 2u * 2u * 8u);
  EXPECT_EQ(parallel, serial);
  EXPECT_EQ(ahead, serial);
}

}  // namespace
