// The scene renderer's time per 736x571 frame (target: at most
// 15 ms on one core) with the paper's camera and sheet, realistic defaults.
//   scripts/bench bench_renderer
#include <benchmark/benchmark.h>

#include <cmath>
#include <opencv2/core/utility.hpp>

#include "sim/scene/renderer.hpp"

namespace {

// Camera looking at the sheet from `distance_m`, tilted by tilt_deg about the
// target's x and y axes (the sheet centred in the view).
vision::Pose pose_at(double distance_m, double tilt_deg) {
  const double a = tilt_deg * M_PI / 180;
  vision::Pose T;
  T.R = (Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(0.6 * a, Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
  T.t = Eigen::Vector3d(0.0, 0.0, distance_m);
  return T;
}

const sim::scene::SceneRenderer& renderer(const sim::scene::SceneOptions& options = {}) {
  static const vision::Codebook codebook;
  static const sim::scene::SceneRenderer r(vision::Camera::paper_default(),
                                           vision::Target::paper_default(), codebook, options);
  return r;
}

// args: distance in cm, tilt in degrees.
void BM_RenderFrame(benchmark::State& state) {
  const sim::scene::SceneRenderer& r = renderer();
  const vision::Pose T = pose_at(state.range(0) / 100.0, static_cast<double>(state.range(1)));
  uint64_t seed = 1;
  for (auto _ : state) {
    sim::scene::RenderedFrame frame = r.render(T, seed++);
    benchmark::DoNotOptimize(frame.image.data);
  }
}
BENCHMARK(BM_RenderFrame)
    ->ArgNames({"distance_cm", "tilt_deg"})
    ->Args({10, 0})
    ->Args({10, 40})
    ->Args({40, 20})
    ->Args({70, 30})
    ->Args({100, 0})
    ->Args({100, 40})
    ->Unit(benchmark::kMillisecond);

// The costliest realism: config/realism/paper.toml's scene (defocus up to
// sigma 2 px, thin prism, PRNU/DSNU, dark current, glare and toner gloss, the
// bowed sheet, flicker, the physical sensor path at 1.5x exposure and 2x gain).
sim::scene::SceneOptions paper_profile_scene() {
  sim::scene::SceneOptions o;
  o.blur_sigma_px = 1.0;
  o.vignetting = 0.35;
  o.thin_prism = {0.0005, 0.0, -0.0004, 0.0};
  o.f_number = 4;
  o.focus_distance_m = 0.35;
  o.read_noise_electrons = 63;
  o.dark_current_e_per_s = 100;
  o.prnu_rel = 0.01;
  o.dsnu_electrons = 10;
  o.glare_peak = 0.12;  // glare (every tile's lobe), toner gloss, a bowed sheet, flicker
  o.glare_lobe_deg = 6;
  o.glare_light_tilt_deg = 35;
  o.glare_light_azimuth_deg = 200;
  o.ink_gloss = 3;
  o.bow_sag_m = 0.001;
  o.bow_shape = sim::scene::SceneOptions::BowShape::kCylinderX;
  o.flicker_modulation = 0.3;
  return o;
}

void BM_RenderFramePaperProfile(benchmark::State& state) {
  static const vision::Codebook codebook;
  static const sim::scene::SceneRenderer r(vision::Camera::paper_default(),
                                           vision::Target::paper_default(), codebook,
                                           paper_profile_scene());
  const vision::Pose T = pose_at(state.range(0) / 100.0, static_cast<double>(state.range(1)));
  uint64_t seed = 1;
  for (auto _ : state) {
    sim::scene::RenderedFrame frame = r.render(T, seed++, {1.5, 0.015, 2.0});
    benchmark::DoNotOptimize(frame.image.data);
  }
}
BENCHMARK(BM_RenderFramePaperProfile)
    ->ArgNames({"distance_cm", "tilt_deg"})
    ->Args({10, 0})
    ->Args({40, 20})
    ->Args({100, 40})
    ->Unit(benchmark::kMillisecond);

void BM_RenderMovingFrame(benchmark::State& state) {
  const sim::scene::SceneRenderer& r = renderer();
  const vision::Pose a = pose_at(0.40, 10), b = pose_at(0.41, 12);
  uint64_t seed = 1;
  for (auto _ : state) {
    sim::scene::RenderedFrame frame = r.render_moving(a, b, seed++);
    benchmark::DoNotOptimize(frame.image.data);
  }
}
BENCHMARK(BM_RenderMovingFrame)->Unit(benchmark::kMillisecond);

void BM_BuildRayTable(benchmark::State& state) {
  const vision::Codebook codebook;
  for (auto _ : state) {
    sim::scene::SceneRenderer r(vision::Camera::paper_default(), vision::Target::paper_default(),
                                codebook);
    benchmark::DoNotOptimize(&r);
  }
}
BENCHMARK(BM_BuildRayTable)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

// One core, as the target is stated: OpenCV's own thread pool (GaussianBlur)
// is limited to the calling thread.
int main(int argc, char** argv) {
  cv::setNumThreads(1);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
