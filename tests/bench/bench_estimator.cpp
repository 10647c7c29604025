// External estimator protocol benchmark: what one frame costs rig beyond the
// estimator's own work, at the paper camera's 736x571.
//
//   BM_EstimatorRoundTrip  one frame's request (image path, calibration,
//                          target layout, rig's corners of the 4 markers seen
//                          at 0.5 m) written, answered at once by a Python
//                          estimator (tests/rig/estimator/scripted_estimator.py
//                          ok: json.loads, one pose, json.dumps), and its
//                          answer read and checked. Target: <= 1 ms per frame.
//   BM_EstimatorFramePng   the lossless PNG rig writes per frame when the
//                          sweep does not save its frames (FrameFolder).
//
//   scripts/bench bench_estimator   (or build/tests/bench/bench_estimator)
#include <benchmark/benchmark.h>

#include <string>

#include "rig/estimator/external_estimator.hpp"
#include "rig/estimator/frame_folder.hpp"
#include "sim/scene/renderer.hpp"
#include "vision/codebook.hpp"
#include "vision/detector.hpp"

namespace {

struct Scene {
  vision::Camera camera = vision::Camera::paper_default();
  vision::Target target = vision::Target::paper_default();
  cv::Mat image;
  std::vector<vision::Detection> detections;
};

const Scene& scene() {
  static const Scene* s = [] {
    auto* scene = new Scene;
    const vision::Codebook codebook;
    const sim::scene::SceneRenderer renderer(scene->camera, scene->target, codebook);
    vision::Pose T;
    T.t = {0.0, 0.0, 0.5};
    scene->image = renderer.render(T, 7).image;
    scene->detections = vision::Detector(scene->camera, codebook).detect(scene->image);
    return scene;
  }();
  return *s;
}

void BM_EstimatorRoundTrip(benchmark::State& state) {
  const Scene& s = scene();
  rig::estimator::FrameFolder folder;
  rig::estimator::FrameRequest request;
  request.image_path = folder.write(s.image);
  request.detections = &s.detections;
  rig::estimator::EstimatorSpec spec;
  spec.name = "bench";
  spec.command = {"python3",
                  std::string(RIG_SOURCE_DIR) + "/tests/rig/estimator/scripted_estimator.py", "ok"};
  rig::estimator::ExternalEstimator estimator(spec, s.camera, s.target);
  if (const auto f = estimator.start()) {
    state.SkipWithError(f->reason.c_str());
    return;
  }
  for (auto _ : state) {
    const rig::estimator::FrameResult r = estimator.estimate(request);
    if (r.failure) {
      state.SkipWithError(r.failure->reason.c_str());
      return;
    }
    benchmark::DoNotOptimize(r.poses.data());
  }
  state.counters["markers_sent"] = static_cast<double>(s.detections.size());
}
BENCHMARK(BM_EstimatorRoundTrip)->Unit(benchmark::kMicrosecond)->UseRealTime();

void BM_EstimatorFramePng(benchmark::State& state) {
  const Scene& s = scene();
  rig::estimator::FrameFolder folder;
  for (auto _ : state)
    benchmark::DoNotOptimize(folder.write(s.image));
}
BENCHMARK(BM_EstimatorFramePng)->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
