// Detector benchmark: our detector against OpenCV's ArUco
// detector (CORNER_REFINE_SUBPIX) and AprilTag 3 (quad_decimate 2), on the
// same frames of sim::scene::SceneRenderer: the paper's sheet, the pose marker
// at 0.10-1.00 m anywhere in the image, tilt up to 40 degrees. Three frame
// sets, each a benchmark name's last part:
//   736x571    the paper's camera, the renderer's default optics and sensor
//              noise (200 frames);
//   2448x2048  a 5 MP GigE camera: the paper's camera scaled to 2448x2048
//              (fx, cx by 2448/736, fy, cy by 2048/571, the same lens
//              distortion, so the same field of view and poses), the
//              renderer's defaults (40 frames);
//   lab        the paper's camera with the renderer's options of the `lab`
//              realism profile (config/realism/lab.toml: its light, glare,
//              flicker, optics, sensor, fixed-pattern noise, thin-prism lens
//              terms and bowed sheet), 200 frames. The detector is given the
//              nominal camera, as on the rig.
// Every detector runs on one thread (AprilTag's nthreads = 1,
// cv::setNumThreads(1) for ArUco and for the OpenCV calls inside ours), so that
// the CPU time is each detector's whole work and the ratios do not depend on
// how many cores the machine lends OpenCV's thread pool.
//
// The markers are ours; ArUco gets them as a custom 4x4 dictionary and
// AprilTag as a custom 16-bit family (data cells 1..4 inside a 6-cell black
// border, white = 1, in tag16h5's cell order), so all three read the same codes with 1-bit
// correction. Corners are compared with the renderer's ground truth after
// the best cyclic order (each library has its own corner order); AprilTag's
// corners are moved by -0.5 px to OpenCV's pixel convention (AprilTag puts
// pixel centres at +0.5, see its quad_decimate rescaling).
//
// Per detector, as counters: median_us (per frame), detection_rate (of the
// markers whose outline is visible and >= 8 px from the border), rms_px_near /
// rms_px_mid / rms_px_far (corner RMS in 0.1-0.4, 0.4-0.7, 0.7-1.0 m), and
// dist_err_pct_<solver> (mean |d - d_true| / d_true in %, pose marker alone,
// for hybrid_oi, hybrid_ekf and lm on that detector's corners).
//   scripts/bench bench_detector   (or build/tests/bench/bench_detector
//                                   --benchmark_counters_tabular=true)
#include <apriltag/apriltag.h>
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <map>
#include <opencv2/aruco.hpp>
#include <opencv2/core/utility.hpp>

#include "detector_frames.hpp"
#include "sim/camera/realism.hpp"
#include "sim/scene/renderer.hpp"
#include "vision/detector.hpp"
#include "vision/solvers.hpp"

namespace {

using Corners = std::array<Eigen::Vector2d, 4>;
struct Found {
  int id;
  Corners corners;
};
using DetectFn = std::function<std::vector<Found>(const cv::Mat&)>;

constexpr double kDetectableBorderPx = 8.0;

struct FrameSet {
  vision::Camera camera = vision::Camera::paper_default();
  vision::Target target = vision::Target::paper_default();
  vision::Codebook codebook;
  std::vector<vision::Pose> poses;
  std::vector<sim::scene::RenderedFrame> frames;
};

// The paper's camera with its image scaled to width x height: the focal
// lengths and the principal point (pixel centres, OpenCV's convention) scaled
// per axis, the distortion (normalized plane) kept.
vision::Camera scaled_camera(const vision::Camera& camera, int width, int height) {
  const double sx = static_cast<double>(width) / camera.width_px();
  const double sy = static_cast<double>(height) / camera.height_px();
  vision::Intrinsics k = camera.intrinsics();
  k.fx *= sx;
  k.fy *= sy;
  k.cx = (k.cx + 0.5) * sx - 0.5;
  k.cy = (k.cy + 0.5) * sy - 0.5;
  return vision::Camera(k, camera.distortion(), width, height);
}

FrameSet* render_set(const std::string& name) {
  auto* s = new FrameSet;
  sim::scene::SceneOptions options;
  int frames = 200;
  if (name == "2448x2048") {
    s->camera = scaled_camera(s->camera, 2448, 2048);
    frames = 40;
  } else if (name == "lab") {
    options =
        sim::camera::load_realism_profile(std::string(RIG_SOURCE_DIR) + "/config/realism/lab.toml")
            .scene;
  }
  const sim::scene::SceneRenderer renderer(s->camera, s->target, s->codebook, options);
  s->poses = detector_test::sample_poses(s->camera, frames, 2024);
  for (int i = 0; i < frames; ++i)
    s->frames.push_back(renderer.render(s->poses[i], 7000 + i));
  return s;
}

const FrameSet& frame_set(const std::string& name) {
  static std::map<std::string, const FrameSet*> sets;
  auto& set = sets[name];
  if (!set) set = render_set(name);
  return *set;
}

// `found` reordered to the truth's order A, B, C, D (best of the 4 cyclic
// shifts in both directions).
Corners align(const Corners& found, const Corners& truth) {
  Corners best = found;
  double best_rms = 1e300;
  for (int dir = 0; dir < 2; ++dir)
    for (int shift = 0; shift < 4; ++shift) {
      Corners c;
      for (int k = 0; k < 4; ++k)
        c[k] = found[dir ? (shift - k + 8) % 4 : (shift + k) % 4];
      const double rms = detector_test::corner_rms(c, truth);
      if (rms < best_rms) best_rms = rms, best = c;
    }
  return best;
}

// Untimed pass over every frame: detection rate, corner RMS per distance
// class, end-to-end distance error of three solvers.
void accuracy_counters(benchmark::State& state, const FrameSet& s, const DetectFn& detect) {
  const std::vector<std::string> solver_names = {"hybrid_oi", "hybrid_ekf", "lm"};
  std::vector<std::unique_ptr<vision::PoseSolver>> solvers;
  for (const auto& n : solver_names)
    solvers.push_back(vision::make_solver(n));
  std::vector<double> dist_err(solvers.size(), 0.0);
  int poses = 0, detectable = 0, found = 0;
  double sum_sq[3] = {0, 0, 0};
  int count[3] = {0, 0, 0};
  Eigen::Vector2d bias =
      Eigen::Vector2d::Zero();  // mean corner offset, px (pixel convention check)
  for (size_t i = 0; i < s.frames.size(); ++i) {
    const auto detections = detect(s.frames[i].image);
    for (const auto& truth : s.frames[i].markers) {
      if (!truth.fully_visible) continue;
      const bool counted = truth.border_distance_px >= kDetectableBorderPx;
      detectable += counted;
      const Found* hit = nullptr;
      for (const auto& d : detections)
        if (d.id == truth.id) hit = &d;
      if (!hit) continue;
      const Corners c = align(hit->corners, truth.corners_px);
      if (detector_test::corner_rms(c, truth.corners_px) > 3) continue;  // not this marker
      found += counted;
      const auto& m = s.target.marker(truth.id);
      const double d = (s.poses[i] * Eigen::Vector3d(m.centre_m.x(), m.centre_m.y(), 0)).norm();
      const int k = detector_test::distance_class(d);
      sum_sq[k] += std::pow(detector_test::corner_rms(c, truth.corners_px), 2);
      ++count[k];
      for (int j = 0; j < 4; ++j)
        bias += (c[j] - truth.corners_px[j]) / 4;
      if (truth.id != s.target.pose_marker_id) continue;
      const auto object = s.target.corners_m(m);
      const vision::Correspondences corr = vision::make_correspondences(
          s.camera, {object.begin(), object.end()}, {c.begin(), c.end()});
      ++poses;
      for (size_t j = 0; j < solvers.size(); ++j) {
        const vision::Estimate e = solvers[j]->solve(corr);
        dist_err[j] += 100 * std::abs(e.distance_m - d) / d;
      }
    }
  }
  state.counters["detection_rate"] = static_cast<double>(found) / std::max(detectable, 1);
  const char* names[3] = {"rms_px_near", "rms_px_mid", "rms_px_far"};
  for (int k = 0; k < 3; ++k)
    state.counters[names[k]] = count[k] ? std::sqrt(sum_sq[k] / count[k]) : -1;
  const int total = count[0] + count[1] + count[2];
  state.counters["bias_x_px"] = total ? bias.x() / total : 0;
  state.counters["bias_y_px"] = total ? bias.y() / total : 0;
  for (size_t j = 0; j < solvers.size(); ++j)
    state.counters["dist_err_pct_" + solver_names[j]] = poses ? dist_err[j] / poses : -1;
}

void run(benchmark::State& state, const FrameSet& s, const DetectFn& detect) {
  accuracy_counters(state, s, detect);
  std::vector<double> us;
  size_t i = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    auto d = detect(s.frames[i++ % s.frames.size()].image);
    benchmark::DoNotOptimize(d);
    us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  std::nth_element(us.begin(), us.begin() + us.size() / 2, us.end());
  state.counters["median_us"] = us[us.size() / 2];
}

void BM_Detector_Ours(benchmark::State& state, const std::string& set) {
  const FrameSet& s = frame_set(set);
  const vision::Detector detector(s.camera, s.codebook);
  run(state, s, [&](const cv::Mat& image) {
    std::vector<Found> out;
    for (const auto& d : detector.detect(image))
      out.push_back({d.id, d.corners_px});
    return out;
  });
}

void BM_Detector_ArucoSubpix(benchmark::State& state, const std::string& set) {
  const FrameSet& s = frame_set(set);
  cv::Mat bytes;
  for (size_t id = 0; id < s.codebook.size(); ++id) {
    cv::Mat bits(vision::kCodeCells, vision::kCodeCells, CV_8UC1);
    for (int r = 0; r < vision::kCodeCells; ++r)
      for (int c = 0; c < vision::kCodeCells; ++c)
        bits.at<uint8_t>(r, c) =
            vision::Codebook::cell_is_white(s.codebook.code(static_cast<int>(id)), r, c) ? 1 : 0;
    bytes.push_back(cv::aruco::Dictionary::getByteListFromBits(bits));
  }
  const auto dictionary = cv::makePtr<cv::aruco::Dictionary>(bytes, vision::kCodeCells,
                                                             s.codebook.max_correction_bits());
  const auto params = cv::aruco::DetectorParameters::create();
  params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  run(state, s, [&](const cv::Mat& image) {
    std::vector<std::vector<cv::Point2f>> corners;
    std::vector<int> ids;
    cv::aruco::detectMarkers(image, dictionary, corners, ids, params);
    std::vector<Found> out;
    for (size_t k = 0; k < ids.size(); ++k) {
      Found f{ids[k], {}};
      for (int j = 0; j < 4; ++j)
        f.corners[j] = Eigen::Vector2d(corners[k][j].x, corners[k][j].y);
      out.push_back(f);
    }
    return out;
  });
}

void BM_Detector_AprilTag3(benchmark::State& state, const std::string& set) {
  const FrameSet& s = frame_set(set);
  // AprilTag 3 turns a code by a quarter by rotating its bit string by a
  // quarter (nbits / 4), so bits i, i + 4, i + 8, i + 12 must be one cell and
  // its three quarter turns: tag16h5's cell order, whose group of four is
  // turned clockwise by (x, y) -> (5 - y, x).
  const uint32_t bit_x[16] = {1, 2, 3, 2, 4, 4, 4, 3, 4, 3, 2, 3, 1, 1, 1, 2};
  const uint32_t bit_y[16] = {1, 1, 1, 2, 1, 2, 3, 2, 4, 4, 4, 3, 4, 3, 2, 3};
  std::vector<uint64_t> codes;
  for (uint16_t ours : s.codebook.codes()) {
    uint64_t code = 0;  // the first cell read is the most significant bit
    for (int i = 0; i < 16; ++i)
      if (vision::Codebook::cell_is_white(ours, static_cast<int>(bit_y[i]) - 1,
                                          static_cast<int>(bit_x[i]) - 1))
        code |= uint64_t{1} << (15 - i);
    codes.push_back(code);
  }
  char name[] = "rig16h5";
  apriltag_family_t family{};
  family.ncodes = static_cast<uint32_t>(codes.size());
  family.codes = codes.data();
  family.width_at_border = 6;
  family.total_width = 8;
  family.reversed_border = false;
  family.nbits = 16;
  family.bit_x = const_cast<uint32_t*>(bit_x);
  family.bit_y = const_cast<uint32_t*>(bit_y);
  family.h = static_cast<uint32_t>(s.codebook.options().min_hamming_distance);
  family.name = name;
  apriltag_detector_t* td = apriltag_detector_create();
  apriltag_detector_add_family_bits(td, &family, s.codebook.max_correction_bits());
  td->quad_decimate = 2;
  td->nthreads = 1;
  run(state, s, [&](const cv::Mat& image) {
    image_u8_t im{image.cols, image.rows, static_cast<int32_t>(image.step[0]),
                  const_cast<uint8_t*>(image.ptr<uint8_t>())};
    zarray_t* detections = apriltag_detector_detect(td, &im);
    std::vector<Found> out;
    for (int k = 0; k < zarray_size(detections); ++k) {
      apriltag_detection_t* det;
      zarray_get(detections, k, &det);
      Found f{det->id, {}};
      for (int j = 0; j < 4; ++j)
        f.corners[j] = Eigen::Vector2d(det->p[j][0] - 0.5, det->p[j][1] - 0.5);
      out.push_back(f);
    }
    apriltag_detections_destroy(detections);
    return out;
  });
  apriltag_detector_destroy(td);
}

// Iterations per frame set: about a second of each detector.
const int kRegistered = [] {
  struct Case {
    const char* set;
    int ours, aruco, apriltag;
  };
  for (const Case& c : {Case{"736x571", 1000, 200, 100}, Case{"2448x2048", 100, 20, 10},
                        Case{"lab", 1000, 200, 100}}) {
    const std::string set = c.set;
    benchmark::RegisterBenchmark(("BM_Detector_Ours/" + set).c_str(), BM_Detector_Ours, set)
        ->Unit(benchmark::kMicrosecond)
        ->Iterations(c.ours);
    benchmark::RegisterBenchmark(("BM_Detector_ArucoSubpix/" + set).c_str(),
                                 BM_Detector_ArucoSubpix, set)
        ->Unit(benchmark::kMicrosecond)
        ->Iterations(c.aruco);
    benchmark::RegisterBenchmark(("BM_Detector_AprilTag3/" + set).c_str(), BM_Detector_AprilTag3,
                                 set)
        ->Unit(benchmark::kMicrosecond)
        ->Iterations(c.apriltag);
  }
  return 0;
}();

}  // namespace

int main(int argc, char** argv) {
  cv::setNumThreads(1);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
