// sim::camera realism profiles: how imperfect the simulated rig is, as data
// (config/realism/{ideal,lab,paper}.toml), and the hidden truth drawn from it.
//
// The controller (rig sweep) only ever reads the *nominal* files: the
// calibration, the rig geometry and the target layout named by its sweep
// file. The simulator renders with a *true* camera, rig geometry and printed
// sheet that differ from the nominal ones by seeded random amounts stated in
// the profile, plus lens terms beyond the 5-parameter Brown-Conrady model
// (thin prism), so that a calibration never fits exactly and a pose is never
// exact, as on a real bench. `rig sim --write-truth FILE` writes that truth
// (truth_json) for tests; nothing in rig/ reads it.
//
// Profile file (TOML; every key optional, its default is the "ideal" world,
// i.e. exactly the nominal files and sim::scene::SceneOptions{}; a key or
// table not listed is refused):
//   name = "lab"                       # reported by the camera (device version)
//   [camera_truth]                     # true camera = nominal + N(0, sigma)
//   seed = 1                           # draws of [camera_truth] and [rig_truth]
//   focal_sigma_rel = 0.003            # fx, fy each: fx_true = fx (1 + sigma z)
//   principal_point_sigma_px = 2.0     # cx, cy each, pixels
//   k1_sigma = 0.005                   # radial k1, dimensionless
//   k2_sigma = 0.0                     # radial k2
//   tangential_sigma = 0.0             # p1, p2 each
//   thin_prism = [s1, s2, s3, s4]      # fixed extra terms (sim::scene::SceneOptions::thin_prism)
//   radial_k4 = 0.0                    # radial r^8 term (SceneOptions::radial_k4)
//   [rig_truth]
//   mount_rotation_sigma_deg = 0.2     # each axis of the camera mount's rotation vector
//   mount_offset_sigma_mm = 0.5        # each axis of the camera's optical centre offset
//   target_tilt_sigma_deg = 0.1        # each axis of the target's rotation vector
//   target_origin_sigma_mm = 0.5       # each axis of the target origin
//   [target]
//   print_scale_error = 0.002          # the printed sheet is (1 + s) times its layout
//   bow_sag_mm = 0.0                   # SceneOptions::bow_sag_m, in millimetres
//   bow_shape = "dome"                 # "dome" | "cylinder_x" | "cylinder_y"
//   paper_gloss = 1.0, ink_gloss = 1.0 # SceneOptions::paper_gloss, ink_gloss
//   [light]   paper_reflectance, ink_reflectance, background_reflectance,
//             lighting_gradient_per_m, lighting_direction_deg, glare_peak,
//             glare_lobe_deg, glare_light_tilt_deg, glare_light_azimuth_deg,
//             flicker_modulation, flicker_frequency_hz, flicker_phase_deg
//   [optics]  blur_sigma_px, vignetting, f_number, focus_distance_m,
//             pixel_pitch_um (SceneOptions::pixel_pitch_m in micrometres)
//   [sensor]  exposure, full_well_electrons, read_noise_electrons, adc_bits, noise,
//             dark_current_e_per_s, prnu_rel, dsnu_electrons, fixed_pattern_seed,
//             bayer = "RG", filter_response = [r, g, b]
//             (adc_bits 1 .. 16: above 8 the camera's Mono10/Mono12/Mono16 carry
//             every bit; bayer, filter_response: RealismProfile below)
//   [bench.x], [bench.y]  backlash_mm, repeatability_mm, encoder_scale_ppm,
//             thermal_drift_um_per_min, vibration_amplitude_mm,
//             vibration_frequency_hz, vibration_decay_s,
//             pitch_arcsec_per_100mm, pitch_arcsec_per_100mm2,
//             yaw_arcsec_per_100mm, yaw_arcsec_per_100mm2 (AxisAngularError)
//   [bench]   abbe_offset_mm = [x, y, z] (CarriageAttitude)
// ([light], [optics], [sensor]: the sim::scene::SceneOptions fields of the same
// names, with their units and ranges; [bench.*]: the sim::bench::AxisConfig
// fields, which replace the bench file's [sim.x] / [sim.y] values when given.)
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "config/error.hpp"
#include "sim/bench/config.hpp"
#include "sim/scene/renderer.hpp"
#include "vision/camera.hpp"
#include "vision/rig_geometry.hpp"
#include "vision/target.hpp"

namespace sim::camera {

// A profile that cannot be read, holds an unknown key or a value out of range.
// The message names the file, the key, the value and what was expected.
class RealismError : public config::ConfigError {
 public:
  using config::ConfigError::ConfigError;
};

// Standard deviations of the hidden truth around the nominal files. Every
// value 0 (the default) makes the truth equal the nominal file exactly.
struct TruthSpread {
  uint64_t seed = 1;
  double focal_sigma_rel = 0;           // relative, each of fx and fy
  double principal_point_sigma_px = 0;  // pixels, each of cx and cy
  double k1_sigma = 0;                  // dimensionless
  double k2_sigma = 0;                  // dimensionless
  double tangential_sigma = 0;          // dimensionless, each of p1 and p2
  double mount_rotation_sigma_deg = 0;  // degrees, each component of the rotation vector
  double mount_offset_sigma_mm = 0;     // mm, each bench axis
  double target_tilt_sigma_deg = 0;     // degrees, each component
  double target_origin_sigma_mm = 0;    // mm, each bench axis
};

// The bench's mechanical imperfections of one axis; an absent value keeps
// the bench file's.
struct AxisRealism {
  std::optional<double> backlash_mm, repeatability_mm, encoder_scale_ppm, thermal_drift_um_per_min,
      vibration_amplitude_mm, vibration_frequency_hz, vibration_decay_s;
};

// The angular error motion of one axis's carriage (ISO 230-1 EAY / EAZ for X:
// pitch and yaw) as a smooth function of that axis's position s (mm):
//   angle(s) = a (s / 100 mm) + b (s / 100 mm)^2   arcseconds,
// a = *_arcsec_per_100mm, b = *_arcsec_per_100mm2; 0 at s = 0 (the angle at
// home is part of the mount's misalignment). A guide's straightness gives a
// few arcseconds per 100 mm on a precision stage, tens on a robot or a
// light gantry.
struct AxisAngularError {
  double pitch_arcsec_per_100mm = 0, pitch_arcsec_per_100mm2 = 0;
  double yaw_arcsec_per_100mm = 0, yaw_arcsec_per_100mm2 = 0;
  bool zero() const {
    return pitch_arcsec_per_100mm == 0 && pitch_arcsec_per_100mm2 == 0 &&
           yaw_arcsec_per_100mm == 0 && yaw_arcsec_per_100mm2 == 0;
  }
  double pitch_rad(double s_mm) const;
  double yaw_rad(double s_mm) const;
};

// How the carriage turns as it travels, and where the camera sits relative
// to the point the encoders measure: the source of Abbe error. The bench's
// encoders read the position of the guide's reference point (the pivot);
// the carriage turns about it by the rotation vector, in bench axes,
//   w(x, y) = (pitch_y(y), pitch_x(x), yaw_x(x) + yaw_y(y))   radians
// (X's pitch about bench y, Y's about bench x, both yaws about z; right-handed,
// small angles), so the camera's optical centre, abbe_offset_mm from the
// pivot, moves by w x offset (Abbe error = lever arm x angle: a pitch of
// the X carriage with the camera h above the guide moves it h * angle along
// x, towards or away from the target) and the camera turns by w. The encoder
// and so the bench's read-back never see it.
struct CarriageAttitude {
  AxisAngularError x, y;
  Eigen::Vector3d abbe_offset_mm = Eigen::Vector3d::Zero();  // optical centre - pivot, bench axes
  bool zero() const { return x.zero() && y.zero(); }
  // w(x, y) above, radians, bench axes.
  Eigen::Vector3d rotation_vector_rad(double x_mm, double y_mm) const;
  // The true T_cam_target with the carriage at (x_mm, y_mm): `geometry`'s,
  // with the carriage turned by w about the pivot. Equals
  // geometry.T_cam_target(x_mm, y_mm) when zero().
  vision::Pose T_cam_target(const vision::RigGeometry& geometry, double x_mm, double y_mm) const;
};

struct RealismProfile {
  std::string name = "ideal";
  TruthSpread truth;
  // Relative print scale error s of the sheet: everything printed is (1 + s)
  // times its layout size (printer and paper shrink: 0.1-0.5 % is typical).
  double print_scale_error = 0;
  // Rendering: light, optics, sensor, and the thin-prism terms of the true lens.
  scene::SceneOptions scene;
  AxisRealism bench_x, bench_y;
  // A colour sensor ([sensor] bayer = "RG"): the camera starts in BayerRG8
  // and its R, G, B pixels carry filter_response times the grey level
  // (sim::camera::CameraServerOptions). Mono (false) by default.
  bool bayer_rg = false;
  std::array<double, 3> filter_response{1.0, 1.0, 1.0};
  CarriageAttitude attitude;  // pitch and yaw of the carriages, Abbe offset
};

// Replaces the bench's [sim.x] / [sim.y] imperfections by the profile's.
void apply_bench_realism(const RealismProfile& profile, bench::BenchSimConfig* bench);

// The ideal profile: the nominal files and the renderer's default options.
RealismProfile ideal_realism();

// Reads a profile file (format above; at most 1 MiB). Throws RealismError.
RealismProfile load_realism_profile(const std::string& path);

// What the simulator really renders with.
struct SimTruth {
  vision::Camera camera;               // true intrinsics and Brown-Conrady distortion
  std::array<double, 4> thin_prism{};  // true extra lens terms s1..s4 (SceneOptions::thin_prism)
  vision::RigGeometry geometry;        // true camera mount and target pose
  vision::Target target;               // the sheet as printed (scaled by 1 + print_scale_error)
  double print_scale_error = 0;
};

// Draws the truth from the nominal files with the profile's spreads (seeded by
// profile.truth.seed: the same profile and files give the same truth).
SimTruth draw_truth(const vision::Camera& nominal_camera,
                    const vision::RigGeometry& nominal_geometry,
                    const vision::Target& nominal_target, const RealismProfile& profile);

// The target scaled by (1 + scale_error) about its frame's origin: marker
// sides and centres, the sheet's size and origin.
vision::Target scaled_target(const vision::Target& target, double scale_error);

// The truth as JSON: profile name, camera (width, height, fx, fy, cx, cy, k1,
// k2, p1, p2, k3, thin_prism, radial_k4), T_carriage_cam and T_bench_target
// (R row-major, t in metres), print_scale_error.
std::string truth_json(const SimTruth& truth, const RealismProfile& profile);

}  // namespace sim::camera
