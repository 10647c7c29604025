// rig::calibrate against the simulated rig's hidden truth: for each of ten
// truth seeds of the `lab` realism profile (camera, lens with thin-prism
// and radial r^8 terms, mount, target pose and print scale drawn by
// sim::camera), the shipped calibration plan and A3 target rendered by the
// real renderer and detected by the real detector with the nominal
// calibration (tests/rig/calibrate/sim_truth_calibration.hpp), calibrated in
// two passes as `rig calibrate` does with a run's saved frames (the frames
// detected again through the first pass's camera), compared with the truth
// the simulator rendered with, under both lens models of rig calibrate
// (--distortion 5 and thin_prism). Every other plan position (111 of 221, one
// frame each, ~8,500 corners per seed) keeps the ten seeds and both models
// at about 40 s of CPU.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>

#include "db/stats/descriptive.hpp"
#include "opencv_reference.hpp"
#include "sim_truth_calibration.hpp"

namespace {

using rig::calibrate::CalibrationOptions;
using rig::calibrate::CalibrationResult;
using rig::calibrate::DistortionModel;

constexpr int kSeeds = 10;

// Errors: fx, fy, scale relative; cx, cy px; pitch, yaw, roll deg (the
// camera rotation relative to the bench, about the camera axes); distance
// camera-to-target at bench zero, m. Stated: the calibration's own sd.
struct SeedErrors {
  std::map<std::string, double> error, stated_sd;
  double sigma_px = 0;  // the fit's residual scale
};

// One seed's calibration sweep: every other plan position, one frame.
rig_test::SimTruthSweep render_seed(std::uint64_t seed, std::optional<double> bow_sag_mm,
                                    std::optional<double> radial_k4 = std::nullopt) {
  rig_test::SimTruthSweepSpec spec;
  spec.source_dir = RIG_SOURCE_DIR;
  spec.truth_seed = seed;
  spec.bow_sag_mm = bow_sag_mm;
  spec.radial_k4 = radial_k4;
  spec.position_stride = 2;
  return rig_test::render_calibration_sweep(spec);
}

// How a seed's corners are calibrated: once from the sweep's detections, or
// in two passes, the second on the frames detected again through the first
// pass's camera (rig calibrate with saved frames).
enum class Passes { kOne, kTwo };

SeedErrors calibrate_sweep(const rig_test::SimTruthSweep& sweep, DistortionModel model,
                           Passes passes = Passes::kOne) {
  CalibrationOptions options;
  options.distortion = model;
  const auto start = std::chrono::steady_clock::now();
  CalibrationResult r;
  if (passes == Passes::kTwo) {
    // The first pass only gives the camera to detect through: no covariance.
    CalibrationOptions first = options;
    first.covariance = false;
    r = rig::calibrate::calibrate(
        rig_test::redetected(sweep, rig::calibrate::calibrate(sweep.problem, first).camera),
        options);
  } else {
    r = rig::calibrate::calibrate(sweep.problem, options);
  }
  const auto done = std::chrono::steady_clock::now();
  const vision::Intrinsics& k = r.camera.intrinsics();
  const vision::Intrinsics& t = sweep.truth.camera.intrinsics();
  const Eigen::Vector3d rotation =
      rig_test::camera_rotation_error_deg(r.geometry, sweep.truth.geometry);
  const vision::Distortion& d = r.camera.distortion();
  const std::array<double, 4>& s = sweep.truth.thin_prism;
  SeedErrors e;
  e.sigma_px = r.sigma_px;
  e.error = {{"fx", k.fx / t.fx - 1},
             {"fy", k.fy / t.fy - 1},
             {"cx", k.cx - t.cx},
             {"cy", k.cy - t.cy},
             {"pitch", rotation.x()},
             {"yaw", rotation.y()},
             {"roll", rotation.z()},
             {"distance", r.geometry.distance_m(0, 0) - sweep.truth.geometry.distance_m(0, 0)},
             {"scale", r.target_scale_error - sweep.truth.print_scale_error}};
  const auto sd = [&](const char* name) {
    return r.parameters[static_cast<std::size_t>(rig::calibrate::parameter_index(name))].sd;
  };
  e.stated_sd = {{"fx", sd("fx") / k.fx},
                 {"fy", sd("fy") / k.fy},
                 {"cx", sd("cx")},
                 {"cy", sd("cy")},
                 {"pitch", sd("camera_misalignment_x_deg")},
                 {"yaw", sd("camera_misalignment_y_deg")},
                 {"roll", sd("camera_misalignment_z_deg")},
                 {"scale", sd("target_scale_error")}};
  if (model == DistortionModel::kBrownConrady5) {
    const rig_test::LensInModel lens = rig_test::lens_in_five_coefficients(sweep);
    const Eigen::Vector3d in_model = rig_test::camera_rotation_error_deg(
        r.geometry, rig_test::geometry_in_model(sweep.truth.geometry, lens));
    e.error.insert({{"pitch_in_model", in_model.x()},
                    {"yaw_in_model", in_model.y()},
                    {"roll_in_model", in_model.z()},
                    {"cx_in_model", k.cx - lens.camera.intrinsics().cx},
                    {"cy_in_model", k.cy - lens.camera.intrinsics().cy}});
    std::printf(
        "  the lens in the model: turned %+.5f %+.5f %+.5f deg, cx %+.3f cy %+.3f px, "
        "rms %.4f px\n",
        lens.rotation_deg.x(), lens.rotation_deg.y(), lens.rotation_deg.z(),
        lens.camera.intrinsics().cx - t.cx, lens.camera.intrinsics().cy - t.cy, lens.rms_px);
  }
  if (model == DistortionModel::kThinPrism) {
    e.error.insert(
        {{"s1", d.s1 - s[0]}, {"s2", d.s2 - s[1]}, {"s3", d.s3 - s[2]}, {"s4", d.s4 - s[3]}});
    e.stated_sd.insert({{"s1", sd("s1")}, {"s2", sd("s2")}, {"s3", sd("s3")}, {"s4", sd("s4")}});
    const auto corr = [&](const char* a, const char* b) {
      return r.correlation(rig::calibrate::parameter_index(a), rig::calibrate::parameter_index(b));
    };
    std::printf(
        "  correlations: pitch-cy %+.3f pitch-s3 %+.3f cy-s3 %+.3f yaw-cx %+.3f "
        "yaw-s1 %+.3f cx-s1 %+.3f\n",
        corr("camera_misalignment_x_deg", "cy"), corr("camera_misalignment_x_deg", "s3"),
        corr("cy", "s3"), corr("camera_misalignment_y_deg", "cx"),
        corr("camera_misalignment_y_deg", "s1"), corr("cx", "s1"));
  }
  std::printf(
      "seed %2d %-10s: %zu frames, %zu of %zu fully visible markers detected, sigma %.4f px; "
      "calibrate %.1f s\n"
      "  fx %+.5f %% fy %+.5f %% cx %+.3f cy %+.3f px, pitch %+.5f yaw %+.5f roll %+.5f deg, "
      "distance %+.2f um, scale %+.2e; s1..s4 %+.2e %+.2e %+.2e %+.2e\n",
      static_cast<int>(sweep.truth_seed), model == DistortionModel::kThinPrism ? "thin_prism" : "5",
      sweep.frames, sweep.detections, sweep.markers_fully_visible, r.sigma_px,
      std::chrono::duration<double>(done - start).count(), 100 * e.error["fx"], 100 * e.error["fy"],
      e.error["cx"], e.error["cy"], e.error["pitch"], e.error["yaw"], e.error["roll"],
      1e6 * e.error["distance"], e.error["scale"], d.s1, d.s2, d.s3, d.s4);
  return e;
}

SeedErrors calibrate_seed(std::uint64_t seed, std::optional<double> bow_sag_mm) {
  return calibrate_sweep(render_seed(seed, bow_sag_mm), CalibrationOptions{}.distortion);
}

// Errors and stated sds of one model over the seeds.
struct OverSeeds {
  std::map<std::string, std::vector<double>> errors, stated;
  void add(const SeedErrors& e) {
    for (const auto& [name, value] : e.error)
      errors[name].push_back(value);
    for (const auto& [name, value] : e.stated_sd)
      stated[name].push_back(value);
  }
  double worst(const std::string& name) const {
    double w = 0;
    for (const double v : errors.at(name))
      w = std::max(w, std::abs(v));
    return w;
  }
  // Spread of the errors over the seeds / mean stated sd.
  double spread_over_stated(const std::string& name) const {
    double stated_mean = 0;
    for (const double v : stated.at(name))
      stated_mean += v / static_cast<double>(stated.at(name).size());
    return db::stats::summarize(errors.at(name)).sd / stated_mean;
  }
  void print(const char* model) const {
    for (const auto& [name, values] : errors) {
      double mean = 0;
      for (const double v : values)
        mean += v / static_cast<double>(values.size());
      const double spread = db::stats::summarize(values).sd;
      const bool has_sd = stated.count(name) > 0;
      std::printf("%-10s %-9s mean error %+.3g worst %.3g spread %.3g spread/stated %.2f\n", model,
                  name.c_str(), mean, worst(name), spread, has_sd ? spread_over_stated(name) : 0.0);
    }
  }
  double mean(const std::string& name) const {
    double m = 0;
    for (const double v : errors.at(name))
      m += v / static_cast<double>(errors.at(name).size());
    return m;
  }
  // The mean error in standard errors of the mean (spread / sqrt(seeds)).
  double mean_in_standard_errors(const std::string& name) const {
    const double spread = db::stats::summarize(errors.at(name)).sd;
    return std::abs(mean(name)) / (spread / std::sqrt(static_cast<double>(kSeeds)));
  }
};

// Both lens models on the same renders of the ten truths, two passes each.
// The targets: fx, fy 0.02 %, principal point 0.2 px, camera rotation 0.005
// deg per axis, distance at bench zero 20 um, print scale 1e-5 (the bias of
// the detector's corners at 0.7 px of blur: measured 3.5e-6), and stated
// standard deviations within a factor 2 of the spread over the seeds. What
// "the camera's rotation" is depends on the lens model:
//  - the 5-coefficient model (the default) cannot hold the lab lens's thin
//    prism (s1 = 1e-4, s3 = -5e-5), which to first order is a turn of the
//    camera (rig_test::lens_in_five_coefficients): no model without a prism
//    can see the mechanical rotation, and every seed measures yaw +0.011 and
//    pitch +0.007 degree from it, with cx +0.15 and cy -0.08 px. The truth in
//    that model's frame is the mechanical one turned by what the prism looks
//    like (computed from the true lens alone, noise-free); the rotation and
//    principal point are checked against it, and against the mechanical
//    truth only the principal point (0.2 px).
//  - the thin prism fitted: the frame is the mechanical one, but s1 and s3
//    take the perspective terms that told the rotation from the principal
//    point (correlations yaw-s1 -0.995 to -0.998, pitch-s3 +0.95 to +0.97),
//    so pitch, yaw and cy scatter by their stated sd (~0.006 deg, 0.08 px)
//    and are checked against 4 stated sd per seed (a Gaussian exceeds it with
//    probability 6e-5).
// The sheet is rendered flat here: its bow (a test below) is outside every
// file's model, the calibration's and the truth's alike.
TEST(CalibrateSimTruth, RecoversTheHiddenTruthOfTheLabProfileOverTenSeeds) {
  OverSeeds five, prism;
  std::vector<SeedErrors> prism_seeds;
  for (std::uint64_t seed = 1; seed <= kSeeds; ++seed) {
    const rig_test::SimTruthSweep sweep = render_seed(seed, 0.0);
    five.add(calibrate_sweep(sweep, DistortionModel::kBrownConrady5, Passes::kTwo));
    prism_seeds.push_back(calibrate_sweep(sweep, DistortionModel::kThinPrism, Passes::kTwo));
    prism.add(prism_seeds.back());
  }
  five.print("5");
  prism.print("thin_prism");
  const std::map<std::string, double> five_bound = {{"fx", 2e-4},
                                                    {"fy", 2e-4},
                                                    {"cx", 0.2},
                                                    {"cy", 0.2},
                                                    {"cx_in_model", 0.2},
                                                    {"cy_in_model", 0.2},
                                                    {"roll", 0.005},
                                                    {"roll_in_model", 0.005},
                                                    {"pitch_in_model", 0.005},
                                                    {"yaw_in_model", 0.005},
                                                    {"distance", 20e-6},
                                                    {"scale", 1e-5}};
  for (const auto& [name, b] : five_bound)
    EXPECT_LT(five.worst(name), b) << "5 coefficients: " << name;
  const std::map<std::string, double> prism_bound = {{"fx", 2e-4},        {"fy", 2e-4},
                                                     {"cx", 0.2},         {"roll", 0.005},
                                                     {"distance", 20e-6}, {"scale", 1e-5}};
  for (const auto& [name, b] : prism_bound)
    EXPECT_LT(prism.worst(name), b) << "thin prism: " << name;
  for (const SeedErrors& e : prism_seeds)
    for (const char* name : {"pitch", "yaw", "cy", "s1", "s2", "s3", "s4"})
      EXPECT_LT(std::abs(e.error.at(name)), 4 * e.stated_sd.at(name)) << "thin prism: " << name;
  // Stated sd (clustered by bench position, CalibrationResult::sd_method)
  // against the spread of the errors over the ten seeds, each seed its own
  // truth and sensor noise: within the brief's factor 2 for every parameter
  // of both models (measured 0.6-1.1).
  for (const OverSeeds* model : {&five, &prism})
    for (const auto& [name, values] : model->stated) {
      EXPECT_GT(model->spread_over_stated(name), 0.5)
          << (model == &five ? "5: " : "prism: ") << name;
      EXPECT_LT(model->spread_over_stated(name), 2.0)
          << (model == &five ? "5: " : "prism: ") << name;
    }
}

// The lab lens's radial r^8 term (config/realism/lab.toml radial_k4 = 0.01,
// 0.14 px at the image corner) is beyond every model rig calibrate fits,
// but k1..k3 absorb most of it: rendered with and without it (seeds 1-2,
// the default model), the fit's residual grows by less than a third of
// itself in quadrature (the term's share of the residual; measured 0.0000
// and 0.0004 px of 0.012 px), cx, cy, pitch and yaw move by less than their
// stated sd: the detector's corner bias, not the unfitted lens term,
// dominates what the fit leaves.
TEST(CalibrateSimTruth, TheUnfittedRadialR8TermStaysBelowTheOtherResiduals) {
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    const DistortionModel model = CalibrationOptions{}.distortion;
    const SeedErrors with = calibrate_sweep(render_seed(seed, 0.0), model);
    const SeedErrors without = calibrate_sweep(render_seed(seed, 0.0, 0.0), model);
    const double share = std::sqrt(
        std::max(0.0, with.sigma_px * with.sigma_px - without.sigma_px * without.sigma_px));
    std::printf("seed %d: sigma %.5f px with r^8, %.5f without; its share %.5f px\n",
                static_cast<int>(seed), with.sigma_px, without.sigma_px, share);
    EXPECT_LT(share, with.sigma_px / 3) << "seed " << seed;
    for (const char* name : {"cx", "cy", "pitch", "yaw"})
      EXPECT_LT(std::abs(with.error.at(name) - without.error.at(name)), with.stated_sd.at(name))
          << name << " seed " << seed;
    // k1..k3 absorb the r^8 term partly by a scale change: fx and fy move by
    // 0.0004-0.0005 % (measured), a 40th of the 0.02 % target; bound a tenth.
    for (const char* name : {"fx", "fy"})
      EXPECT_LT(std::abs(with.error.at(name) - without.error.at(name)), 2e-5)
          << name << " seed " << seed;
  }
}

// The lab sheet bows towards the camera by bow_sag_mm at its centre (a dome
// held at its edges). The truth's target pose is the flat plane of the
// edges; the calibration fits a plane to the markers, which lie between that
// plane and the sag, so its camera-to-target distance at bench zero is
// shorter by at most the sag (measured on seeds 1-10 with 0.1 mm: -98 to
// -108 um; the markers cluster where the dome is highest). That is where the
// solvers see the sheet too. Bound: the flat sheet's 20 um on either side of
// [-sag, 0]. The intrinsics do not depend on the bow (measured: within the
// flat sheet's bounds); the print scale shifts by ~1e-5, left unchecked.
TEST(CalibrateSimTruth, ABowedSheetMovesTheTargetPlaneTowardsTheCameraByAtMostItsSag) {
  const double sag_mm = 0.1;  // config/realism/lab.toml [target] bow_sag_mm
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    const SeedErrors e = calibrate_seed(seed, sag_mm);
    EXPECT_LT(e.error.at("distance"), 20e-6) << "seed " << seed;
    EXPECT_GT(e.error.at("distance"), -sag_mm / 1000 - 20e-6) << "seed " << seed;
    for (const char* name : {"fx", "fy"})
      EXPECT_LT(std::abs(e.error.at(name)), 2e-4) << name << " seed " << seed;
    for (const char* name : {"cx", "cy"})
      EXPECT_LT(std::abs(e.error.at(name)), 0.2) << name << " seed " << seed;
  }
}

// rig calibrate beside cv::calibrateCamera on the same rendered detections of
// the shipped lab truth (seed 7), the whole plan, fit on the even positions,
// held out the odd ones: the README's table.
TEST(CalibrateSimTruth, BeatsOpenCvCalibrateCameraOnTheHiddenTruthData) {
  rig_test::SimTruthSweepSpec spec;
  spec.source_dir = RIG_SOURCE_DIR;
  spec.truth_seed = 7;
  const rig_test::SimTruthSweep sweep = rig_test::render_calibration_sweep(spec);
  const auto even = rig::calibrate::alternate_positions(sweep.problem, true);
  const auto odd = rig::calibrate::alternate_positions(sweep.problem, false);
  const CalibrationResult ours = rig::calibrate::calibrate(even, CalibrationOptions{});
  const rig_test::OpenCvFit cv_fit = rig_test::opencv_calibrate(even, odd);
  const double ours_held_out = rig::calibrate::reprojection_rms_px(odd, ours.camera, ours.geometry,
                                                                   {}, ours.target_scale_error);
  const double cv_held_out =
      rig::calibrate::reprojection_rms_px(odd, cv_fit.camera, sweep.problem.nominal_geometry);
  const vision::Camera& truth = sweep.truth.camera;
  const vision::Intrinsics& t = truth.intrinsics();
  const std::array<double, 4> ours_err = rig_test::intrinsics_error_px(ours.camera, t);
  const std::array<double, 4> cv_err = rig_test::intrinsics_error_px(cv_fit.camera, t);
  std::printf("| figure | `rig calibrate` | `cv::calibrateCamera` (one view per position) |\n");
  std::printf("|---|---|---|\n");
  const char* names[4] = {"fx error, px", "fy error, px", "cx error, px", "cy error, px"};
  for (int i = 0; i < 4; ++i)
    std::printf("| %s | %+.3f | %+.3f |\n", names[i], ours_err[i], cv_err[i]);
  std::printf("| k1 error | %+.1e | %+.1e |\n", ours.camera.distortion().k1 - truth.distortion().k1,
              cv_fit.camera.distortion().k1 - truth.distortion().k1);
  std::printf("| k2 error | %+.1e | %+.1e |\n", ours.camera.distortion().k2 - truth.distortion().k2,
              cv_fit.camera.distortion().k2 - truth.distortion().k2);
  std::printf("| fit RMS, px | %.4f | %.4f |\n", ours.rms_px, cv_fit.rms_px);
  std::printf(
      "| held-out RMS predicted from the read-backs, px | %.4f | %.4f (nominal geometry) |\n",
      ours_held_out, cv_held_out);
  std::printf("| held-out RMS, pose refitted per view, px | - | %.4f |\n",
              cv_fit.pnp_held_out_rms_px);
  // Measured: OpenCV's focal lengths are 30-58 times further off (+0.58
  // px against -0.010 and -0.020 px); its principal point is about as far
  // off as ours (both carry the thin prism's shift: cx +0.05 and +0.13 px,
  // cy -0.09 px each), and without a rig geometry it predicts the held-out
  // positions 21 times worse.
  EXPECT_LT(ours_held_out, cv_held_out);
  EXPECT_LT(std::abs(ours_err[0]), std::abs(cv_err[0]));
  EXPECT_LT(std::abs(ours_err[1]), std::abs(cv_err[1]));
  for (int i = 2; i < 4; ++i) {
    EXPECT_LT(std::abs(ours_err[i]), 0.2) << names[i];
    EXPECT_LT(std::abs(cv_err[i]), 0.2) << names[i];
  }
  // Predicted from the read-backs alone, within 3x the fit's own residual:
  // the held-out positions are as well explained as the fitted ones.
  EXPECT_LT(ours_held_out, 3 * ours.rms_px);
}

}  // namespace
