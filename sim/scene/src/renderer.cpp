// sim::scene::SceneRenderer (see sim/scene/renderer.hpp): orchestration and
// ground truth. The geometry stage, the artwork integrals, the ray table, the
// sensor and the disturbances live in geometry, sheet, rays, sensor and
// disturbances (.hpp/.cpp beside this file).
#include "sim/scene/renderer.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>
#include <stdexcept>
#include <string>

#include "disturbances.hpp"
#include "geometry.hpp"
#include "lens.hpp"
#include "rays.hpp"
#include "sensor.hpp"
#include "sheet.hpp"

namespace sim::scene {

namespace {

void check(bool ok, const std::string& name, double value, const std::string& expected) {
  if (!ok) {
    throw std::invalid_argument("SceneOptions." + name + " = " + std::to_string(value) +
                                ": expected " + expected);
  }
}

void validate(const SceneOptions& o) {
  check(o.supersampling >= 1 && o.supersampling <= 16, "supersampling", o.supersampling, "1 .. 16");
  for (const auto& [name, value] :
       {std::pair<const char*, double>{"paper_reflectance", o.paper_reflectance},
        {"ink_reflectance", o.ink_reflectance},
        {"background_reflectance", o.background_reflectance},
        {"vignetting", o.vignetting}}) {
    check(value >= 0 && value <= 1, name, value, "0 .. 1");
  }
  check(std::isfinite(o.lighting_gradient_per_m), "lighting_gradient_per_m",
        o.lighting_gradient_per_m, "a finite number");
  check(std::isfinite(o.lighting_direction_deg), "lighting_direction_deg", o.lighting_direction_deg,
        "a finite number");
  check(o.blur_sigma_px >= 0 && o.blur_sigma_px <= 20, "blur_sigma_px", o.blur_sigma_px, "0 .. 20");
  check(o.exposure > 0 && o.exposure <= 10, "exposure", o.exposure, "in (0, 10]");
  check(o.full_well_electrons >= 100, "full_well_electrons", o.full_well_electrons, ">= 100");
  check(o.read_noise_electrons >= 0, "read_noise_electrons", o.read_noise_electrons, ">= 0");
  check(o.adc_bits >= 1 && o.adc_bits <= 16, "adc_bits", o.adc_bits, "1 .. 16");
  check(o.clutter_shapes >= 0, "clutter_shapes", o.clutter_shapes, ">= 0");
  check(o.occluders >= 0, "occluders", o.occluders, ">= 0");
  check(o.occluder_min_width_px > 0 && o.occluder_max_width_px >= o.occluder_min_width_px,
        "occluder_max_width_px", o.occluder_max_width_px, ">= occluder_min_width_px > 0");
  for (double s : o.thin_prism)
    check(std::abs(s) <= 0.05, "thin_prism", s, "each of s1..s4 within -0.05 .. 0.05");
  check(std::abs(o.radial_k4) <= 0.5, "radial_k4", o.radial_k4, "within -0.5 .. 0.5");
  check(o.f_number >= 0 && o.f_number <= 64, "f_number", o.f_number, "0 (no defocus) .. 64");
  check(o.focus_distance_m > 0, "focus_distance_m", o.focus_distance_m, "> 0");
  check(o.pixel_pitch_m > 0 && o.pixel_pitch_m < 1e-3, "pixel_pitch_m", o.pixel_pitch_m,
        "in (0, 1e-3) m");
  check(o.exposure_time_s > 0 && o.exposure_time_s <= 100, "exposure_time_s", o.exposure_time_s,
        "in (0, 100] s");
  check(o.dark_current_e_per_s >= 0, "dark_current_e_per_s", o.dark_current_e_per_s, ">= 0");
  check(o.prnu_rel >= 0 && o.prnu_rel <= 0.2, "prnu_rel", o.prnu_rel, "0 .. 0.2");
  check(o.dsnu_electrons >= 0, "dsnu_electrons", o.dsnu_electrons, ">= 0");
  check(o.motion_blur_samples >= 1, "motion_blur_samples", o.motion_blur_samples, ">= 1");
  check(o.glare_peak >= 0 && o.glare_peak <= 100, "glare_peak", o.glare_peak, "0 (off) .. 100");
  check(o.glare_lobe_deg > 0 && o.glare_lobe_deg <= 90, "glare_lobe_deg", o.glare_lobe_deg,
        "in (0, 90] degrees");
  check(o.glare_light_tilt_deg >= 0 && o.glare_light_tilt_deg < 90, "glare_light_tilt_deg",
        o.glare_light_tilt_deg, "0 .. 90 degrees from the sheet's normal");
  check(std::isfinite(o.glare_light_azimuth_deg), "glare_light_azimuth_deg",
        o.glare_light_azimuth_deg, "a finite number");
  check(o.paper_gloss >= 0 && o.paper_gloss <= 100, "paper_gloss", o.paper_gloss, "0 .. 100");
  check(o.ink_gloss >= 0 && o.ink_gloss <= 100, "ink_gloss", o.ink_gloss, "0 .. 100");
  check(o.flicker_modulation >= 0 && o.flicker_modulation <= 1, "flicker_modulation",
        o.flicker_modulation, "0 .. 1");
  check(o.flicker_frequency_hz > 0 && o.flicker_frequency_hz <= 1e5, "flicker_frequency_hz",
        o.flicker_frequency_hz, "in (0, 1e5] Hz");
  check(std::isfinite(o.flicker_phase_deg), "flicker_phase_deg", o.flicker_phase_deg,
        "a finite number");
  check(o.bow_sag_m >= 0 && o.bow_sag_m <= 0.05, "bow_sag_m", o.bow_sag_m, "0 .. 0.05 m");
}

// Outline of a marker's black square, kPerSide points per side, target frame.
constexpr int kOutlinePerSide = 32;

}  // namespace

struct SceneRenderer::Impl {
  vision::Camera camera;
  vision::Target target;
  SceneOptions options;
  detail::Lens lens;
  detail::RayTable rays;
  detail::SheetArtwork front;
  detail::SheetArtwork back;
  detail::NormalTable normal;
  detail::FixedPattern pattern;
  detail::SheetBow bow;

  Impl(const vision::Camera& c, const vision::Target& t, const vision::MarkerFamily& family,
       const SceneOptions& o)
      : camera(c),
        target(t),
        options(o),
        lens(c, o.thin_prism, o.radial_k4),
        rays(detail::build_ray_table(lens, o.vignetting)),
        front(t, family, true),
        back(t, family, false),
        pattern(detail::make_fixed_pattern(c.width_px(), c.height_px(), o.prnu_rel,
                                           o.dsnu_electrons, o.fixed_pattern_seed)),
        bow(o, t) {}

  cv::Mat sensor(const cv::Mat& ideal, uint64_t seed, const SensorExposure& e) const {
    // The lamps' flicker scales every photon of the exposure alike.
    const double flicker = flicker_gain(options, e.start_time_s, e.exposure_time_s);
    const detail::SensorModel model{options.full_well_electrons,
                                    options.read_noise_electrons,
                                    options.adc_bits,
                                    options.noise,
                                    e.signal_scale * flicker,
                                    options.dark_current_e_per_s * e.exposure_time_s,
                                    e.gain};
    return detail::apply_sensor(ideal, model, normal, seed, pattern);
  }

  std::vector<MarkerTruth> truth(const vision::Pose& T) const;
  std::vector<detail::Occluder> place_occluders(const std::vector<MarkerTruth>& markers,
                                                std::mt19937_64& rng) const;
  void mark_occlusions(const vision::Pose& T, const std::vector<detail::Occluder>& occluders,
                       std::vector<MarkerTruth>& markers) const;
  cv::Mat irradiance(const vision::Pose* poses, int count, uint64_t seed,
                     std::vector<MarkerTruth>* markers, const vision::Pose& truth_pose) const;
};

std::vector<MarkerTruth> SceneRenderer::Impl::truth(const vision::Pose& T) const {
  std::vector<MarkerTruth> result;
  if (!options.show_target) return result;
  if ((-(T.R.transpose() * T.t)).z() >= 0) return result;  // printed side faces away
  const double w = camera.width_px() - 1, h = camera.height_px() - 1;
  for (const vision::TargetMarker& m : target.markers) {
    const Eigen::Vector3d centre =
        T * bow.surface(Eigen::Vector3d(m.centre_m.x(), m.centre_m.y(), 0));
    if (centre.z() <= 0) continue;
    MarkerTruth t;
    t.id = m.id;
    const auto corners = target.corners_m(m);  // on the plane; bow.surface raises them
    bool in_front = true;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d p = T * bow.surface(corners[k]);
      in_front = in_front && p.z() > 0;
      t.corners_px[k] = p.z() > 0
                            ? lens.project(p)
                            : Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
    }
    double distance = in_front ? std::numeric_limits<double>::infinity() : -1e9;
    for (int k = 0; k < 4 && in_front; ++k) {
      for (int s = 0; s < kOutlinePerSide; ++s) {
        const double f = static_cast<double>(s) / kOutlinePerSide;
        const Eigen::Vector2d px =
            lens.project(T * bow.surface((1 - f) * corners[k] + f * corners[(k + 1) % 4]));
        distance = std::min({distance, px.x(), px.y(), w - px.x(), h - px.y()});
      }
    }
    t.border_distance_px = distance;
    t.fully_visible = in_front && distance >= 0;
    result.push_back(t);
  }
  return result;
}

std::vector<detail::Occluder> SceneRenderer::Impl::place_occluders(
    const std::vector<MarkerTruth>& markers, std::mt19937_64& rng) const {
  std::vector<detail::Occluder> result;
  std::vector<const MarkerTruth*> candidates;
  for (const MarkerTruth& m : markers) {
    if (m.border_distance_px > -1e8) candidates.push_back(&m);
  }
  std::uniform_real_distribution<double> unit(0, 1);
  for (int k = 0; k < options.occluders; ++k) {
    detail::Occluder o;
    const double angle = unit(rng) * M_PI;
    o.axis = Eigen::Vector2d(std::cos(angle), std::sin(angle));
    o.half_width_px =
        0.5 * (options.occluder_min_width_px +
               unit(rng) * (options.occluder_max_width_px - options.occluder_min_width_px));
    o.reflectance = 0.1 + 0.5 * unit(rng);
    if (candidates.empty()) {
      o.centre_px = Eigen::Vector2d(unit(rng) * camera.width_px(), unit(rng) * camera.height_px());
      o.half_length_px = 0.1 * camera.width_px();
    } else {
      // Through a point of a marker's outline, so that it cuts the marker.
      const MarkerTruth& m = *candidates[static_cast<size_t>(rng() % candidates.size())];
      const int side = static_cast<int>(rng() % 4);
      const double f = 0.2 + 0.6 * unit(rng);
      const Eigen::Vector2d a = m.corners_px[side], b = m.corners_px[(side + 1) % 4];
      const double side_px = (b - a).norm();
      o.half_length_px = std::max(0.3 * side_px, 2 * o.half_width_px);
      o.centre_px = a + f * (b - a) + (unit(rng) - 0.5) * o.half_length_px * o.axis;
    }
    result.push_back(o);
  }
  return result;
}

void SceneRenderer::Impl::mark_occlusions(const vision::Pose& T,
                                          const std::vector<detail::Occluder>& occluders,
                                          std::vector<MarkerTruth>& markers) const {
  if (occluders.empty()) return;
  // The PSF spreads an occluder's edge by ~3 sigma: closer than that it biases
  // the marker's edges, so it counts as occluding.
  const double margin = 3 * options.blur_sigma_px + 1;
  const cv::Size size(camera.width_px(), camera.height_px());
  cv::Mat mask(size, CV_8UC1);
  for (MarkerTruth& m : markers) {
    const auto corners = target.corners_m(target.marker(m.id));
    std::vector<cv::Point> outline;
    bool ok = true;
    for (int k = 0; k < 4; ++k) {
      for (int s = 0; s < kOutlinePerSide; ++s) {
        const double f = static_cast<double>(s) / kOutlinePerSide;
        const Eigen::Vector3d p = T * bow.surface((1 - f) * corners[k] + f * corners[(k + 1) % 4]);
        ok = ok && p.z() > 0;
        if (!ok) break;
        const Eigen::Vector2d px = lens.project(p);
        outline.emplace_back(static_cast<int>(std::lround(std::clamp(px.x(), -1e5, 1e5) * 16)),
                             static_cast<int>(std::lround(std::clamp(px.y(), -1e5, 1e5) * 16)));
      }
    }
    if (!ok) continue;
    mask.setTo(0);
    cv::fillPoly(mask, std::vector<std::vector<cv::Point>>{outline}, cv::Scalar(255), cv::LINE_8,
                 4);
    for (const detail::Occluder& o : occluders) {
      const cv::Rect box = o.bounds(size, margin);
      for (int v = box.y; v < box.y + box.height && !m.occluded; ++v) {
        const uint8_t* row = mask.ptr<uint8_t>(v);
        for (int u = box.x; u < box.x + box.width; ++u) {
          if (row[u] != 0 && o.coverage(u, v, margin) > 0) {
            m.occluded = true;
            break;
          }
        }
      }
    }
    if (m.occluded) m.fully_visible = false;
  }
}

cv::Mat SceneRenderer::Impl::irradiance(const vision::Pose* poses, int count, uint64_t seed,
                                        std::vector<MarkerTruth>* markers,
                                        const vision::Pose& truth_pose) const {
  std::mt19937_64 rng(seed ^ 0x5DEECE66Dull);
  const cv::Size size(camera.width_px(), camera.height_px());
  cv::Mat background;
  if (options.clutter_shapes > 0) {
    background =
        detail::make_clutter(size, options.clutter_shapes, options.background_reflectance, rng);
  }
  cv::Mat radiance(size, CV_32FC1, cv::Scalar(0));
  for (int k = 0; k < count; ++k) {
    detail::accumulate_radiance(rays, front, back, options, bow, poses[k], background,
                                1.0f / static_cast<float>(count), radiance);
  }
  std::vector<MarkerTruth> truths = truth(truth_pose);
  const std::vector<detail::Occluder> occluders = place_occluders(truths, rng);
  detail::apply_occluders(occluders, radiance);
  mark_occlusions(truth_pose, occluders, truths);
  if (markers != nullptr) *markers = std::move(truths);

  const double defocus =
      defocus_sigma_px(options, camera.intrinsics().fx, std::max(truth_pose.t.z(), 1e-3));
  const double sigma = std::hypot(options.blur_sigma_px, defocus);
  if (sigma > 0) cv::GaussianBlur(radiance, radiance, cv::Size(), sigma, sigma, cv::BORDER_REFLECT);
  // Vignetting and exposure: DN = 255 * exposure * gain * radiance.
  const float scale = static_cast<float>(255.0 * options.exposure);
  float* r = radiance.ptr<float>();
  const float* g = rays.vignetting_gain.data();
  for (size_t i = 0, n = radiance.total(); i < n; ++i)
    r[i] *= scale * g[i];
  return radiance;
}

double flicker_gain(const SceneOptions& o, double start_time_s, double exposure_time_s) {
  if (o.flicker_modulation == 0) return 1;
  const double w = 2 * M_PI * o.flicker_frequency_hz;
  const double half = 0.5 * w * exposure_time_s;
  const double sinc = half > 1e-9 ? std::sin(half) / half : 1.0;
  const double phase =
      w * (start_time_s + 0.5 * exposure_time_s) + o.flicker_phase_deg * M_PI / 180;
  return 1 + o.flicker_modulation * sinc * std::sin(phase);
}

double sheet_sag_m(const SceneOptions& options, const vision::Target& target, double x_m,
                   double y_m) {
  return detail::SheetBow(options, target)(x_m, y_m);
}

double defocus_sigma_px(const SceneOptions& o, double fx_px, double depth_m) {
  if (o.f_number <= 0) return 0;
  const double f = fx_px * o.pixel_pitch_m;  // focal length, metres
  const double c = f * f / (o.f_number * std::abs(o.focus_distance_m - f)) *
                   std::abs(depth_m - o.focus_distance_m) / depth_m;
  return c / o.pixel_pitch_m / 4;
}

SceneRenderer::SceneRenderer(const vision::Camera& camera, const vision::Target& target,
                             const vision::Codebook& codebook, SceneOptions options)
    : SceneRenderer(camera, target, vision::MarkerFamily::from_codebook(codebook), options) {}

SceneRenderer::SceneRenderer(const vision::Camera& camera, const vision::Target& target,
                             const vision::MarkerFamily& family, SceneOptions options) {
  validate(options);
  impl_ = std::make_unique<Impl>(camera, target, family, options);
}

SceneRenderer::~SceneRenderer() = default;
SceneRenderer::SceneRenderer(SceneRenderer&&) noexcept = default;
SceneRenderer& SceneRenderer::operator=(SceneRenderer&&) noexcept = default;

// Throws std::invalid_argument naming the field of a SensorExposure out of range.
static void check_exposure(const SensorExposure& e) {
  const auto fail = [](const char* name, double value, const char* expected) {
    throw std::invalid_argument(std::string("SensorExposure.") + name + " = " +
                                std::to_string(value) + ": expected " + expected);
  };
  if (!(e.signal_scale > 0 && std::isfinite(e.signal_scale)))
    fail("signal_scale", e.signal_scale, "a finite number > 0");
  if (!(e.exposure_time_s >= 0 && std::isfinite(e.exposure_time_s)))
    fail("exposure_time_s", e.exposure_time_s, "a finite number >= 0");
  if (!(e.gain > 0 && std::isfinite(e.gain))) fail("gain", e.gain, "a finite number > 0");
  if (!std::isfinite(e.start_time_s)) fail("start_time_s", e.start_time_s, "a finite number");
}

RenderedFrame SceneRenderer::render(const vision::Pose& T_cam_target, uint64_t seed) const {
  return render(T_cam_target, seed, SensorExposure{1, impl_->options.exposure_time_s, 1});
}

RenderedFrame SceneRenderer::render(const vision::Pose& T_cam_target, uint64_t seed,
                                    const SensorExposure& exposure) const {
  check_exposure(exposure);
  RenderedFrame frame;
  const cv::Mat ideal = impl_->irradiance(&T_cam_target, 1, seed, &frame.markers, T_cam_target);
  frame.image = impl_->sensor(ideal, seed, exposure);
  return frame;
}

RenderedFrame SceneRenderer::render_moving(const vision::Pose& T_cam_target_start,
                                           const vision::Pose& T_cam_target_end,
                                           uint64_t seed) const {
  return render_moving(T_cam_target_start, T_cam_target_end, seed,
                       SensorExposure{1, impl_->options.exposure_time_s, 1});
}

RenderedFrame SceneRenderer::render_moving(const vision::Pose& T_cam_target_start,
                                           const vision::Pose& T_cam_target_end, uint64_t seed,
                                           const SensorExposure& exposure) const {
  check_exposure(exposure);
  const int n = impl_->options.motion_blur_samples;
  const Eigen::Quaterniond q0(T_cam_target_start.R), q1(T_cam_target_end.R);
  const auto at = [&](double f) {
    vision::Pose p;
    p.R = q0.slerp(f, q1).normalized().toRotationMatrix();
    p.t = (1 - f) * T_cam_target_start.t + f * T_cam_target_end.t;
    return p;
  };
  std::vector<vision::Pose> poses;
  for (int k = 0; k < n; ++k)
    poses.push_back(at((k + 0.5) / n));
  RenderedFrame frame;
  const cv::Mat ideal = impl_->irradiance(poses.data(), n, seed, &frame.markers, at(0.5));
  frame.image = impl_->sensor(ideal, seed, exposure);
  return frame;
}

cv::Mat SceneRenderer::render_irradiance(const vision::Pose& T_cam_target, uint64_t seed) const {
  return impl_->irradiance(&T_cam_target, 1, seed, nullptr, T_cam_target);
}

std::vector<MarkerTruth> SceneRenderer::ground_truth(const vision::Pose& T_cam_target) const {
  return impl_->truth(T_cam_target);
}

const vision::Camera& SceneRenderer::camera() const {
  return impl_->camera;
}
const vision::Target& SceneRenderer::target() const {
  return impl_->target;
}
const SceneOptions& SceneRenderer::options() const {
  return impl_->options;
}

}  // namespace sim::scene
