// Capture through the GigE Vision stack on loopback: vision::GigeSource
// against the simulated camera (sim::camera::CameraServer) at the paper's 736x571
// Mono8.
//   BM_SimCameraFreeRun      frames/s, every frame rendered from the bench pose
//   BM_GigeTransportFreeRun  frames/s of the transport alone: Aravis's GV fake
//                            camera with its built-in pattern (rendering excluded)
//   BM_TriggerToFrame        software trigger -> whole frame in hand, median and
//                            p99 (poll delay <= 1 ms + render + transport; a
//                            real exposure adds its duration on top)
// Run: scripts/bench capture
#include <arv.h>
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <vector>

#include "sim/camera/server.hpp"
#include "vision/gige_source.hpp"

namespace {

using namespace std::chrono_literals;

std::unique_ptr<sim::camera::CameraServer> start_sim_camera() {
  auto renderer = std::make_shared<const sim::scene::SceneRenderer>(
      vision::Camera::paper_default(), vision::Target::paper_default(), vision::Codebook());
  sim::camera::CameraServerOptions options;
  options.real_time_exposure = false;
  auto server = std::make_unique<sim::camera::CameraServer>(
      renderer, vision::RigGeometry::load(std::string(RIG_SOURCE_DIR) + "/config/rigs/sim.toml"),
      [] { return std::make_pair(250.0, 150.0); }, options);
  server->start();
  return server;
}

vision::CaptureOptions free_run() {
  vision::CaptureOptions options;
  options.software_trigger = false;
  options.frame_rate_hz = 1000;  // unpaced: as fast as the camera produces
  options.width = 736;
  options.height = 571;
  return options;
}

void grab_loop(benchmark::State& state, vision::GigeSource& source) {
  source.open();
  source.grab(2000ms);  // the first frame waits for the stream to start
  for (auto _ : state)
    benchmark::DoNotOptimize(source.grab(2000ms).image.data);
  state.SetItemsProcessed(state.iterations());
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["lost"] = static_cast<double>(source.counters().lost);
  state.counters["incomplete"] = static_cast<double>(source.counters().incomplete);
}

void BM_SimCameraFreeRun(benchmark::State& state) {
  auto server = start_sim_camera();
  vision::GigeSource source(server->address(), free_run());
  grab_loop(state, source);
}
BENCHMARK(BM_SimCameraFreeRun)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

void BM_GigeTransportFreeRun(benchmark::State& state) {
  ArvGvFakeCamera* camera = arv_gv_fake_camera_new("127.0.0.1", "RIGBENCH");
  {
    vision::GigeSource source("127.0.0.1", free_run());
    grab_loop(state, source);
  }
  g_object_unref(camera);
}
BENCHMARK(BM_GigeTransportFreeRun)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

void BM_TriggerToFrame(benchmark::State& state) {
  auto server = start_sim_camera();
  vision::GigeSource source(server->address());
  source.open();
  source.trigger();
  source.grab(2000ms);  // the first frame waits for the stream to start
  std::vector<double> ms;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    source.trigger();
    benchmark::DoNotOptimize(source.grab(2000ms).image.data);
    ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(ms.begin(), ms.end());
  state.counters["median_ms"] = ms[ms.size() / 2];
  state.counters["p99_ms"] = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
}
BENCHMARK(BM_TriggerToFrame)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(300);

}  // namespace

BENCHMARK_MAIN();
