// Realism profiles and the hidden truth (see sim/camera/realism.hpp).
#include "sim/camera/realism.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>
#include <utility>

#include "config/reader.hpp"

namespace sim::camera {
namespace {

config::NumberRule within(double lo, double hi) {
  return {"a number in " + config::format_number(lo) + " .. " + config::format_number(hi),
          [lo, hi](double v) { return v >= lo && v <= hi; }};
}

void read_camera_truth(config::Table t, RealismProfile* p) {
  TruthSpread& s = p->truth;
  s.seed =
      static_cast<uint64_t>(t.integer_or("seed", static_cast<std::int64_t>(s.seed), 0, INT64_MAX));
  s.focal_sigma_rel = t.number_or("focal_sigma_rel", 0, within(0, 0.1));
  s.principal_point_sigma_px = t.number_or("principal_point_sigma_px", 0, within(0, 50));
  s.k1_sigma = t.number_or("k1_sigma", 0, within(0, 0.5));
  s.k2_sigma = t.number_or("k2_sigma", 0, within(0, 0.5));
  s.tangential_sigma = t.number_or("tangential_sigma", 0, within(0, 0.05));
  if (t.has("thin_prism")) {
    const std::vector<double> v = t.numbers("thin_prism", 4, 4, "[s1, s2, s3, s4], four numbers");
    for (size_t k = 0; k < 4; ++k) {
      if (std::abs(v[k]) > 0.05) t.fail("thin_prism", "each of s1..s4 within -0.05 .. 0.05");
      p->scene.thin_prism[k] = v[k];
    }
  }
  p->scene.radial_k4 = t.number_or("radial_k4", 0, within(-0.5, 0.5));
  t.reject_unknown();
}

void read_rig_truth(config::Table t, TruthSpread* s) {
  s->mount_rotation_sigma_deg = t.number_or("mount_rotation_sigma_deg", 0, within(0, 10));
  s->mount_offset_sigma_mm = t.number_or("mount_offset_sigma_mm", 0, within(0, 100));
  s->target_tilt_sigma_deg = t.number_or("target_tilt_sigma_deg", 0, within(0, 10));
  s->target_origin_sigma_mm = t.number_or("target_origin_sigma_mm", 0, within(0, 100));
  t.reject_unknown();
}

// [sensor] bayer = "RG" and filter_response = [r, g, b]: a colour filter
// array in front of the sensor (what the camera puts on the wire only).
void read_colour_filter(config::Table& sensor, RealismProfile* p) {
  const std::string bayer = sensor.string_or("bayer", "", "\"RG\" (an RGGB mosaic), or absent");
  if (!bayer.empty() && bayer != "RG")
    sensor.fail("bayer", "\"RG\" (an RGGB mosaic, GenICam BayerRG8), or absent for a mono sensor");
  p->bayer_rg = bayer == "RG";
  if (!sensor.has("filter_response")) return;
  if (!p->bayer_rg) sensor.fail("filter_response", "no filter_response without bayer = \"RG\"");
  const std::vector<double> v =
      sensor.numbers("filter_response", 3, 3, "[r, g, b], three numbers in 0 .. 1");
  for (size_t k = 0; k < 3; ++k) {
    if (!(v[k] >= 0 && v[k] <= 1)) sensor.fail("filter_response", "[r, g, b], each in 0 .. 1");
    p->filter_response[k] = v[k];
  }
}

void read_scene(config::Table light, config::Table optics, config::Table sensor,
                scene::SceneOptions* o) {
  o->paper_reflectance = light.number_or("paper_reflectance", o->paper_reflectance, within(0, 1));
  o->ink_reflectance = light.number_or("ink_reflectance", o->ink_reflectance, within(0, 1));
  o->background_reflectance =
      light.number_or("background_reflectance", o->background_reflectance, within(0, 1));
  o->lighting_gradient_per_m =
      light.number_or("lighting_gradient_per_m", o->lighting_gradient_per_m);
  o->lighting_direction_deg = light.number_or("lighting_direction_deg", o->lighting_direction_deg);
  o->glare_peak = light.number_or("glare_peak", o->glare_peak, within(0, 100));
  o->glare_lobe_deg = light.number_or("glare_lobe_deg", o->glare_lobe_deg, within(0.01, 90));
  o->glare_light_tilt_deg =
      light.number_or("glare_light_tilt_deg", o->glare_light_tilt_deg, within(0, 89.9));
  o->glare_light_azimuth_deg =
      light.number_or("glare_light_azimuth_deg", o->glare_light_azimuth_deg, within(-360, 360));
  o->flicker_modulation =
      light.number_or("flicker_modulation", o->flicker_modulation, within(0, 1));
  o->flicker_frequency_hz =
      light.number_or("flicker_frequency_hz", o->flicker_frequency_hz, within(1, 1e5));
  o->flicker_phase_deg =
      light.number_or("flicker_phase_deg", o->flicker_phase_deg, within(-360, 360));
  light.reject_unknown();
  o->blur_sigma_px = optics.number_or("blur_sigma_px", o->blur_sigma_px, within(0, 20));
  o->vignetting = optics.number_or("vignetting", o->vignetting, within(0, 1));
  o->f_number = optics.number_or("f_number", o->f_number, within(0, 64));
  o->focus_distance_m =
      optics.number_or("focus_distance_m", o->focus_distance_m, within(0.01, 100));
  o->pixel_pitch_m =
      optics.number_or("pixel_pitch_um", o->pixel_pitch_m * 1e6, within(0.5, 50)) * 1e-6;
  optics.reject_unknown();
  o->exposure = sensor.number_or("exposure", o->exposure, within(1e-6, 10));
  o->full_well_electrons =
      sensor.number_or("full_well_electrons", o->full_well_electrons, within(100, 1e7));
  o->read_noise_electrons =
      sensor.number_or("read_noise_electrons", o->read_noise_electrons, within(0, 1e5));
  o->adc_bits = static_cast<int>(sensor.integer_or("adc_bits", o->adc_bits, 1, 16));
  o->noise = sensor.boolean_or("noise", o->noise);
  o->dark_current_e_per_s =
      sensor.number_or("dark_current_e_per_s", o->dark_current_e_per_s, within(0, 1e6));
  o->prnu_rel = sensor.number_or("prnu_rel", o->prnu_rel, within(0, 0.2));
  o->dsnu_electrons = sensor.number_or("dsnu_electrons", o->dsnu_electrons, within(0, 1e4));
  o->fixed_pattern_seed = static_cast<uint64_t>(sensor.integer_or(
      "fixed_pattern_seed", static_cast<std::int64_t>(o->fixed_pattern_seed), 0, INT64_MAX));
  sensor.reject_unknown();
}

AxisRealism read_bench_axis(config::Table t, AxisAngularError* angular) {
  AxisRealism a;
  const config::NumberRule arcsec = within(-3600, 3600);
  angular->pitch_arcsec_per_100mm = t.number_or("pitch_arcsec_per_100mm", 0, arcsec);
  angular->pitch_arcsec_per_100mm2 = t.number_or("pitch_arcsec_per_100mm2", 0, arcsec);
  angular->yaw_arcsec_per_100mm = t.number_or("yaw_arcsec_per_100mm", 0, arcsec);
  angular->yaw_arcsec_per_100mm2 = t.number_or("yaw_arcsec_per_100mm2", 0, arcsec);
  const auto get = [&t](const char* key, const config::NumberRule& rule) {
    return t.optional_number(key, rule);
  };
  a.backlash_mm = get("backlash_mm", within(0, 10));
  a.repeatability_mm = get("repeatability_mm", within(0, 10));
  a.encoder_scale_ppm = get("encoder_scale_ppm", within(-10000, 10000));
  a.thermal_drift_um_per_min = get("thermal_drift_um_per_min", within(-1000, 1000));
  a.vibration_amplitude_mm = get("vibration_amplitude_mm", within(0, 10));
  a.vibration_frequency_hz = get("vibration_frequency_hz", within(0.1, 10000));
  a.vibration_decay_s = get("vibration_decay_s", within(1e-4, 100));
  t.reject_unknown();
  return a;
}

void read_target(config::Table t, RealismProfile* p) {
  p->print_scale_error = t.number_or("print_scale_error", 0, within(-0.05, 0.05));
  scene::SceneOptions& o = p->scene;
  o.bow_sag_m = t.number_or("bow_sag_mm", 0, within(0, 50)) / 1000;
  const std::string shape =
      t.string_or("bow_shape", "dome", "\"dome\", \"cylinder_x\" or \"cylinder_y\"");
  if (shape == "dome") {
    o.bow_shape = scene::SceneOptions::BowShape::kDome;
  } else if (shape == "cylinder_x") {
    o.bow_shape = scene::SceneOptions::BowShape::kCylinderX;
  } else if (shape == "cylinder_y") {
    o.bow_shape = scene::SceneOptions::BowShape::kCylinderY;
  } else {
    t.fail("bow_shape", "\"dome\", \"cylinder_x\" or \"cylinder_y\"");
  }
  o.paper_gloss = t.number_or("paper_gloss", o.paper_gloss, within(0, 100));
  o.ink_gloss = t.number_or("ink_gloss", o.ink_gloss, within(0, 100));
  t.reject_unknown();
}

void apply_axis(const AxisRealism& r, bench::AxisConfig* a) {
  const auto set = [](const std::optional<double>& v, double* field) {
    if (v) *field = *v;
  };
  set(r.backlash_mm, &a->backlash_mm);
  set(r.repeatability_mm, &a->repeatability_mm);
  set(r.encoder_scale_ppm, &a->encoder_scale_ppm);
  set(r.thermal_drift_um_per_min, &a->thermal_drift_um_per_min);
  set(r.vibration_amplitude_mm, &a->vibration_amplitude_mm);
  set(r.vibration_frequency_hz, &a->vibration_frequency_hz);
  set(r.vibration_decay_s, &a->vibration_decay_s);
}

// Standard normal deviates by Box-Muller on std::mt19937_64, whose output the
// C++ standard fixes: the same seed gives the same truth with any library.
class Normal {
 public:
  explicit Normal(uint64_t seed) : rng_(seed) {}
  double operator()() {
    const double u1 = (static_cast<double>(rng_() >> 11) + 0.5) * 0x1.0p-53;
    const double u2 = static_cast<double>(rng_() >> 11) * 0x1.0p-53;
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
  }
  Eigen::Vector3d vector(double sigma) {
    const double x = (*this)(), y = (*this)(), z = (*this)();
    return sigma * Eigen::Vector3d(x, y, z);
  }

 private:
  std::mt19937_64 rng_;
};

Eigen::Matrix3d rotation_deg(const Eigen::Vector3d& r_deg) {
  const double angle = r_deg.norm() * M_PI / 180;
  if (angle == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, r_deg.normalized()).toRotationMatrix();
}

nlohmann::json pose_json(const vision::Pose& T) {
  nlohmann::json R = nlohmann::json::array();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      R.push_back(T.R(r, c));
  return {{"R", R}, {"t_m", {T.t.x(), T.t.y(), T.t.z()}}};
}

double arcsec_profile_rad(double a, double b, double s_mm) {
  const double s = s_mm / 100;
  return (a * s + b * s * s) * M_PI / (180.0 * 3600.0);
}

}  // namespace

double AxisAngularError::pitch_rad(double s_mm) const {
  return arcsec_profile_rad(pitch_arcsec_per_100mm, pitch_arcsec_per_100mm2, s_mm);
}
double AxisAngularError::yaw_rad(double s_mm) const {
  return arcsec_profile_rad(yaw_arcsec_per_100mm, yaw_arcsec_per_100mm2, s_mm);
}

Eigen::Vector3d CarriageAttitude::rotation_vector_rad(double x_mm, double y_mm) const {
  return {y.pitch_rad(y_mm), x.pitch_rad(x_mm), x.yaw_rad(x_mm) + y.yaw_rad(y_mm)};
}

vision::Pose CarriageAttitude::T_cam_target(const vision::RigGeometry& geometry, double x_mm,
                                            double y_mm) const {
  if (zero()) return geometry.T_cam_target(x_mm, y_mm);
  vision::Pose T_bench_cam =
      vision::RigGeometry::T_bench_carriage(x_mm, y_mm) * geometry.T_carriage_cam;
  const Eigen::Vector3d w = rotation_vector_rad(x_mm, y_mm);
  const Eigen::Matrix3d turn = w.norm() > 0
                                   ? Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix()
                                   : Eigen::Matrix3d::Identity();
  const Eigen::Vector3d lever = abbe_offset_mm / 1000;
  const Eigen::Vector3d pivot = T_bench_cam.t - lever;
  T_bench_cam.R = turn * T_bench_cam.R;
  T_bench_cam.t = pivot + turn * lever;
  return T_bench_cam.inverse() * geometry.T_bench_target;
}

RealismProfile ideal_realism() {
  return RealismProfile{};
}

RealismProfile load_realism_profile(const std::string& path) {
  const config::Document file = config::Document::read<RealismError>(path, "the realism profile");
  config::Table root = file.root();
  RealismProfile p;
  p.name = root.string_or("name", p.name, "the profile's name, e.g. \"lab\"");
  if (p.name.empty() || p.name.size() > 22)
    root.fail("name", "a name of 1 to 22 characters (the camera reports \"realism NAME\")");
  read_camera_truth(root.optional_table("camera_truth"), &p);
  read_rig_truth(root.optional_table("rig_truth"), &p.truth);
  read_target(root.optional_table("target"), &p);
  config::Table sensor = root.optional_table("sensor");
  read_colour_filter(sensor, &p);
  // Asked in this order, one statement each: as two arguments of one call
  // their order would be the compiler's (gcc and clang differ), and with it
  // the list of keys an unknown-key error names.
  config::Table optics = root.optional_table("optics");
  config::Table light = root.optional_table("light");
  read_scene(std::move(light), std::move(optics), sensor, &p.scene);
  config::Table bench = root.optional_table("bench");
  p.bench_x = read_bench_axis(bench.optional_table("x"), &p.attitude.x);
  p.bench_y = read_bench_axis(bench.optional_table("y"), &p.attitude.y);
  if (bench.has("abbe_offset_mm")) {
    const std::vector<double> v =
        bench.numbers("abbe_offset_mm", 3, 3, "[x, y, z] in mm, three numbers");
    for (size_t k = 0; k < 3; ++k) {
      if (std::abs(v[k]) > 2000) bench.fail("abbe_offset_mm", "each of x, y, z within +-2000 mm");
      p.attitude.abbe_offset_mm[static_cast<Eigen::Index>(k)] = v[k];
    }
  }
  bench.reject_unknown();
  root.reject_unknown();
  return p;
}

void apply_bench_realism(const RealismProfile& profile, bench::BenchSimConfig* bench) {
  apply_axis(profile.bench_x, &bench->x);
  apply_axis(profile.bench_y, &bench->y);
}

vision::Target scaled_target(const vision::Target& target, double scale_error) {
  const double f = 1 + scale_error;
  vision::Target t = target;
  for (vision::TargetMarker& m : t.markers) {
    m.side_m *= f;
    m.centre_m *= f;
  }
  t.sheet_width_m *= f;
  t.sheet_height_m *= f;
  t.sheet_origin_m *= f;
  return t;
}

SimTruth draw_truth(const vision::Camera& nominal_camera,
                    const vision::RigGeometry& nominal_geometry,
                    const vision::Target& nominal_target, const RealismProfile& profile) {
  const TruthSpread& s = profile.truth;
  Normal z(s.seed);
  // Fixed draw order, so that adding a spread never changes the others' draws.
  vision::Intrinsics k = nominal_camera.intrinsics();
  vision::Distortion d = nominal_camera.distortion();
  k.fx *= 1 + s.focal_sigma_rel * z();
  k.fy *= 1 + s.focal_sigma_rel * z();
  k.cx += s.principal_point_sigma_px * z();
  k.cy += s.principal_point_sigma_px * z();
  d.k1 += s.k1_sigma * z();
  d.k2 += s.k2_sigma * z();
  d.p1 += s.tangential_sigma * z();
  d.p2 += s.tangential_sigma * z();
  vision::RigGeometry g = nominal_geometry;
  // Mount rotation about the camera's own axes; offsets along bench axes.
  g.T_carriage_cam.R = g.T_carriage_cam.R * rotation_deg(z.vector(s.mount_rotation_sigma_deg));
  g.T_carriage_cam.t += z.vector(s.mount_offset_sigma_mm) / 1000;
  g.T_bench_target.R = g.T_bench_target.R * rotation_deg(z.vector(s.target_tilt_sigma_deg));
  g.T_bench_target.t += z.vector(s.target_origin_sigma_mm) / 1000;
  return SimTruth{vision::Camera(k, d, nominal_camera.width_px(), nominal_camera.height_px()),
                  profile.scene.thin_prism, g,
                  scaled_target(nominal_target, profile.print_scale_error),
                  profile.print_scale_error};
}

std::string truth_json(const SimTruth& truth, const RealismProfile& profile) {
  const vision::Intrinsics& k = truth.camera.intrinsics();
  const vision::Distortion& d = truth.camera.distortion();
  const nlohmann::json j = {{"profile", profile.name},
                            {"camera",
                             {{"width_px", truth.camera.width_px()},
                              {"height_px", truth.camera.height_px()},
                              {"fx", k.fx},
                              {"fy", k.fy},
                              {"cx", k.cx},
                              {"cy", k.cy},
                              {"k1", d.k1},
                              {"k2", d.k2},
                              {"p1", d.p1},
                              {"p2", d.p2},
                              {"k3", d.k3},
                              {"thin_prism", truth.thin_prism},
                              {"radial_k4", profile.scene.radial_k4}}},
                            {"T_carriage_cam", pose_json(truth.geometry.T_carriage_cam)},
                            {"T_bench_target", pose_json(truth.geometry.T_bench_target)},
                            {"print_scale_error", truth.print_scale_error}};
  return j.dump(2) + "\n";
}

}  // namespace sim::camera
