// Realism profiles (config/realism/*.toml) and the hidden truth drawn from
// them: the ideal profile is the simulator of record, unknown keys are
// refused, the truth's spreads are the stated ones, the thin-prism lens terms
// move the image as modelled, and a print scale error moves every solver's
// distance as the pinhole model predicts.
#include "sim/camera/realism.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "sim/camera/config.hpp"
#include "vision/codebook.hpp"
#include "vision/frame_measurement.hpp"

namespace {

std::string repo(const std::string& relative) {
  return std::string(RIG_SOURCE_DIR) + "/" + relative;
}

sim::camera::RealismProfile shipped(const std::string& name) {
  return sim::camera::load_realism_profile(repo("config/realism/" + name + ".toml"));
}

vision::RigGeometry nominal_geometry() {
  return vision::RigGeometry::load(repo("config/rigs/sim.toml"));
}

TEST(Realism, IdealProfileIsTheRendererDefaultAndTheNominalFiles) {
  const sim::camera::RealismProfile p = shipped("ideal");
  const sim::scene::SceneOptions d, &o = p.scene;
  EXPECT_EQ(p.name, "ideal");
  EXPECT_EQ(o.supersampling, d.supersampling);
  EXPECT_EQ(o.paper_reflectance, d.paper_reflectance);
  EXPECT_EQ(o.ink_reflectance, d.ink_reflectance);
  EXPECT_EQ(o.background_reflectance, d.background_reflectance);
  EXPECT_EQ(o.lighting_gradient_per_m, d.lighting_gradient_per_m);
  EXPECT_EQ(o.lighting_direction_deg, d.lighting_direction_deg);
  EXPECT_EQ(o.blur_sigma_px, d.blur_sigma_px);
  EXPECT_EQ(o.vignetting, d.vignetting);
  EXPECT_EQ(o.thin_prism, d.thin_prism);
  EXPECT_EQ(o.exposure, d.exposure);
  EXPECT_EQ(o.full_well_electrons, d.full_well_electrons);
  EXPECT_EQ(o.read_noise_electrons, d.read_noise_electrons);
  EXPECT_EQ(o.adc_bits, d.adc_bits);
  EXPECT_EQ(o.noise, d.noise);
  EXPECT_EQ(p.print_scale_error, 0);

  // Zero spreads: the truth is the nominal files, bit for bit.
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::RigGeometry geometry = nominal_geometry();
  const vision::Target target = vision::Target::paper_default();
  const sim::camera::SimTruth truth = sim::camera::draw_truth(camera, geometry, target, p);
  EXPECT_EQ(truth.camera.K(), camera.K());
  EXPECT_EQ(truth.camera.distortion_cv().at<double>(0), camera.distortion().k1);
  EXPECT_EQ(truth.camera.distortion().k2, camera.distortion().k2);
  EXPECT_EQ(truth.camera.distortion().p1, camera.distortion().p1);
  EXPECT_EQ(truth.geometry.T_carriage_cam.R, geometry.T_carriage_cam.R);
  EXPECT_EQ(truth.geometry.T_carriage_cam.t, geometry.T_carriage_cam.t);
  EXPECT_EQ(truth.geometry.T_bench_target.R, geometry.T_bench_target.R);
  EXPECT_EQ(truth.geometry.T_bench_target.t, geometry.T_bench_target.t);
  EXPECT_EQ(truth.target.markers[1].centre_m, target.markers[1].centre_m);
  EXPECT_EQ(truth.target.markers[1].side_m, target.markers[1].side_m);
}

TEST(Realism, ShippedProfilesLoadAndTheSimFileUsesLab) {
  const sim::camera::RealismProfile lab = shipped("lab"), paper = shipped("paper");
  EXPECT_EQ(lab.name, "lab");
  EXPECT_EQ(paper.name, "paper");
  // The paper's bench is the worse one in every spread.
  EXPECT_GT(paper.truth.focal_sigma_rel, lab.truth.focal_sigma_rel);
  EXPECT_GT(paper.truth.mount_rotation_sigma_deg, lab.truth.mount_rotation_sigma_deg);
  EXPECT_GT(paper.print_scale_error, lab.print_scale_error);
  EXPECT_GT(lab.print_scale_error, 0);

  const sim::camera::SimRigConfig c = sim::camera::load_sim_rig_config(repo("config/sim.toml"));
  EXPECT_EQ(c.realism_profile, repo("config/realism/lab.toml"));
  EXPECT_EQ(c.realism.name, "lab");
  EXPECT_EQ(c.camera.device_version, "realism lab");

  sim::camera::SimRigConfig o = c;
  sim::camera::override_realism(&o, repo("config/sim.toml"), "paper");
  EXPECT_EQ(o.realism.name, "paper");
  EXPECT_EQ(o.camera.device_version, "realism paper");
  EXPECT_THROW(sim::camera::override_realism(&o, repo("config/sim.toml"), "nosuchprofile"),
               sim::camera::RealismError);
}

// A profile's [bench.x] / [bench.y] replace the bench file's imperfections,
// key by key; an absent key keeps the file's value.
TEST(Realism, BenchImperfectionsReplaceTheBenchFilesValues) {
  sim::bench::BenchSimConfig bench =
      sim::bench::load_bench_sim_config(repo("config/benches/sim.toml"));
  const double file_repeatability = bench.x.repeatability_mm;
  sim::camera::apply_bench_realism(shipped("ideal"), &bench);
  EXPECT_EQ(bench.x.repeatability_mm, file_repeatability);
  EXPECT_EQ(bench.y.encoder_scale_ppm, 0);
  sim::camera::apply_bench_realism(shipped("lab"), &bench);
  EXPECT_EQ(bench.x.backlash_mm, 0.002);
  EXPECT_EQ(bench.x.encoder_scale_ppm, 5.0);
  EXPECT_EQ(bench.y.encoder_scale_ppm, -3.0);
  EXPECT_EQ(bench.y.vibration_frequency_hz, 45.0);
  EXPECT_EQ(bench.x.max_speed_mm_s,
            sim::bench::load_bench_sim_config(repo("config/benches/sim.toml")).x.max_speed_mm_s);
}

// The message of the RealismError that loading a profile of `text` throws,
// after "PATH: ".
std::string profile_error(const std::string& text) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("rig_realism_test_" + std::to_string(::getpid()) + ".toml"))
                               .string();
  std::ofstream(path) << text;
  std::string message = "(accepted)";
  try {
    sim::camera::load_realism_profile(path);
  } catch (const sim::camera::RealismError& e) {
    message = e.what();
  }
  std::filesystem::remove(path);
  return message.rfind(path + ": ", 0) == 0 ? message.substr(path.size() + 2) : message;
}

TEST(Realism, UnknownKeysAndBadValuesAreRefusedNamingThem) {
  EXPECT_EQ(
      profile_error("[optics]\nblur = 1.0\n"),
      "optics.blur = 1.0: unknown key (misspelt?); expected one of blur_sigma_px, vignetting, "
      "f_number, focus_distance_m, pixel_pitch_um");
  EXPECT_EQ(profile_error("[sensorr]\n"),
            "sensorr = {}: unknown key (misspelt?); expected one of name, camera_truth, rig_truth, "
            "target, sensor, optics, light, bench");
  EXPECT_NE(profile_error("[bench.x]\nbacklash = 1\n").find("bench.x.backlash = 1: unknown key"),
            std::string::npos);
  EXPECT_NE(profile_error("[sensor]\nadc_bits = 17\n").find("sensor.adc_bits = 17: expected"),
            std::string::npos);
  EXPECT_NE(profile_error("[sensor]\nbayer = \"GB\"\n")
                .find("sensor.bayer = \"GB\": expected \"RG\" (an RGGB mosaic"),
            std::string::npos);
  EXPECT_NE(profile_error("[sensor]\nfilter_response = [0.5, 1, 0.5]\n")
                .find("sensor.filter_response = [0.5, 1, 0.5]: expected no filter_response "
                      "without bayer = \"RG\""),
            std::string::npos);
  EXPECT_NE(profile_error("[sensor]\nbayer = \"RG\"\nfilter_response = [0.5, 1.5, 0.5]\n")
                .find("expected [r, g, b], each in 0 .. 1"),
            std::string::npos);
  EXPECT_NE(profile_error("[camera_truth]\nfocal_sigma_rel = -0.5\n")
                .find("camera_truth.focal_sigma_rel = -0.5: expected a number in 0 .. 0.1"),
            std::string::npos);
  EXPECT_NE(profile_error("[camera_truth]\nthin_prism = [0.1, 0, 0, 0]\n")
                .find("camera_truth.thin_prism"),
            std::string::npos);
  EXPECT_NE(profile_error("[camera_truth]\nradial_k4 = 0.75\n")
                .find("camera_truth.radial_k4 = 0.75: expected a number in -0.5 .. 0.5"),
            std::string::npos)
      << profile_error("[camera_truth]\nradial_k4 = 0.75\n");
  EXPECT_EQ(profile_error("name = \"ok\"\n"), "(accepted)");
}

// What goes on the wire: a 12-bit ADC and an RGGB colour filter array.
TEST(Realism, AdcBitsAndColourFilterReachTheCamera) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("rig_realism_colour_" + std::to_string(getpid()) + ".toml");
  std::ofstream(path) << "name = \"colour\"\n[sensor]\nadc_bits = 12\nbayer = \"RG\"\n"
                         "filter_response = [0.55, 1.0, 0.45]\n";
  const sim::camera::RealismProfile p = sim::camera::load_realism_profile(path.string());
  std::filesystem::remove(path);
  EXPECT_EQ(p.scene.adc_bits, 12);
  EXPECT_TRUE(p.bayer_rg);
  EXPECT_EQ(p.filter_response, (std::array<double, 3>{0.55, 1.0, 0.45}));
  EXPECT_FALSE(shipped("ideal").bayer_rg);
  EXPECT_EQ(shipped("ideal").filter_response, (std::array<double, 3>{1.0, 1.0, 1.0}));
}

TEST(Realism, TheSameSeedDrawsTheSameTruthAndJsonHoldsIt) {
  const sim::camera::RealismProfile p = shipped("paper");
  const vision::Camera camera = vision::Camera::paper_default();
  const auto a =
      sim::camera::draw_truth(camera, nominal_geometry(), vision::Target::paper_default(), p);
  const auto b =
      sim::camera::draw_truth(camera, nominal_geometry(), vision::Target::paper_default(), p);
  EXPECT_EQ(a.camera.K(), b.camera.K());
  EXPECT_EQ(a.geometry.T_carriage_cam.R, b.geometry.T_carriage_cam.R);
  EXPECT_NE(a.camera.intrinsics().fx, camera.intrinsics().fx);

  const nlohmann::json j = nlohmann::json::parse(sim::camera::truth_json(a, p));
  EXPECT_EQ(j["profile"], "paper");
  EXPECT_EQ(j["camera"]["fx"].get<double>(), a.camera.intrinsics().fx);
  EXPECT_EQ(j["camera"]["k1"].get<double>(), a.camera.distortion().k1);
  EXPECT_EQ(j["camera"]["thin_prism"][0].get<double>(), p.scene.thin_prism[0]);
  EXPECT_EQ(j["camera"]["radial_k4"].get<double>(), p.scene.radial_k4);
  EXPECT_EQ(j["T_carriage_cam"]["R"][1].get<double>(), a.geometry.T_carriage_cam.R(0, 1));
  EXPECT_EQ(j["T_bench_target"]["t_m"][2].get<double>(), a.geometry.T_bench_target.t.z());
  EXPECT_EQ(j["print_scale_error"].get<double>(), p.print_scale_error);
}

// Over n seeds, the sample standard deviation of each drawn deviation is the
// profile's sigma: a sample std of n normal draws has a relative standard
// error of 1/sqrt(2 n) (2.2 % for n = 1000); 4 of them (9 %) bound it. The
// seeds are fixed, so the test is deterministic.
TEST(Realism, TruthDeviationsHaveTheStatedSigmas) {
  sim::camera::RealismProfile p = shipped("paper");
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::RigGeometry g0 = nominal_geometry();
  const vision::Target target = vision::Target::paper_default();
  constexpr int n = 1000;
  double fx = 0, cx = 0, k1 = 0, rot = 0, off = 0, tilt = 0;
  for (int seed = 1; seed <= n; ++seed) {
    p.truth.seed = static_cast<uint64_t>(seed);
    const auto t = sim::camera::draw_truth(camera, g0, target, p);
    fx += std::pow(t.camera.intrinsics().fx / camera.intrinsics().fx - 1, 2);
    cx += std::pow(t.camera.intrinsics().cx - camera.intrinsics().cx, 2);
    k1 += std::pow(t.camera.distortion().k1 - camera.distortion().k1, 2);
    // Rotation vector of the mount error, in the camera's own axes (degrees).
    const Eigen::AngleAxisd e(g0.T_carriage_cam.R.transpose() * t.geometry.T_carriage_cam.R);
    rot += std::pow((e.angle() * e.axis()).x() * 180 / M_PI, 2);
    off += std::pow((t.geometry.T_carriage_cam.t - g0.T_carriage_cam.t).y() * 1000, 2);
    const Eigen::AngleAxisd f(g0.T_bench_target.R.transpose() * t.geometry.T_bench_target.R);
    tilt += std::pow((f.angle() * f.axis()).z() * 180 / M_PI, 2);
  }
  const double tolerance = 4 / std::sqrt(2.0 * n);
  const auto expect_sigma = [&](double sum_sq, double sigma, const char* what) {
    EXPECT_NEAR(std::sqrt(sum_sq / n) / sigma, 1.0, tolerance) << what;
  };
  expect_sigma(fx, p.truth.focal_sigma_rel, "fx");
  expect_sigma(cx, p.truth.principal_point_sigma_px, "cx");
  expect_sigma(k1, p.truth.k1_sigma, "k1");
  expect_sigma(rot, p.truth.mount_rotation_sigma_deg, "mount rotation x");
  expect_sigma(off, p.truth.mount_offset_sigma_mm, "mount offset y");
  expect_sigma(tilt, p.truth.target_tilt_sigma_deg, "target tilt z");
}

vision::Pose facing(double distance_m, Eigen::Vector2d offset_m = Eigen::Vector2d::Zero()) {
  vision::Pose T;
  T.R = (Eigen::AngleAxisd(10 * M_PI / 180, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(-8 * M_PI / 180, Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
  T.t = Eigen::Vector3d(offset_m.x(), offset_m.y(), distance_m);
  return T;
}

sim::scene::SceneOptions noise_free() {
  sim::scene::SceneOptions o;
  o.noise = false;
  return o;
}

// The thin-prism terms move every ground-truth corner by exactly
// (fx (s1 r2 + s2 r2^2), fy (s3 r2 + s4 r2^2)), and the rendered image with
// them: the shift of a marker's image (phase correlation of a window around
// it, accurate to a few hundredths of a pixel on noise-free edges) matches
// the mean shift of its corners within 0.05 px, while the shift itself is
// several pixels.
TEST(Realism, ThinPrismMovesTheImageAsModelled) {
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::Target target = vision::Target::paper_default();
  sim::scene::SceneOptions prism = noise_free();
  prism.thin_prism = {0.02, 0.0, -0.015, 0.0};
  const sim::scene::SceneRenderer plain(camera, target, vision::Codebook(), noise_free());
  const sim::scene::SceneRenderer bent(camera, target, vision::Codebook(), prism);
  const vision::Pose T = facing(0.45, {0.03, 0.02});
  const auto a = plain.render(T, 1), b = bent.render(T, 1);
  ASSERT_EQ(a.markers.size(), b.markers.size());
  const auto& k = camera.intrinsics();
  for (size_t m = 0; m < a.markers.size(); ++m) {
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector3d p = T * target.corners_m(target.markers[m])[c];
      const double r2 = std::pow(p.x() / p.z(), 2) + std::pow(p.y() / p.z(), 2);
      const Eigen::Vector2d expected(k.fx * 0.02 * r2, -k.fy * 0.015 * r2);
      EXPECT_LT((b.markers[m].corners_px[c] - a.markers[m].corners_px[c] - expected).norm(), 1e-9);
    }
  }
  // Marker 3 (at (0, 90) mm) sits far from the image centre: the largest shift.
  const auto& ma = a.markers[3];
  Eigen::Vector2d mean_shift = Eigen::Vector2d::Zero(), centre = Eigen::Vector2d::Zero();
  for (int c = 0; c < 4; ++c) {
    mean_shift += (b.markers[3].corners_px[c] - ma.corners_px[c]) / 4;
    centre += ma.corners_px[c] / 4;
  }
  ASSERT_GT(mean_shift.norm(), 1.0);
  const cv::Rect window(static_cast<int>(centre.x()) - 48, static_cast<int>(centre.y()) - 48, 96,
                        96);
  cv::Mat wa, wb;
  a.image(window).convertTo(wa, CV_64F);
  b.image(window).convertTo(wb, CV_64F);
  const cv::Point2d shift = cv::phaseCorrelate(wa, wb);
  EXPECT_NEAR(shift.x, mean_shift.x(), 0.05);
  EXPECT_NEAR(shift.y, mean_shift.y(), 0.05);
}

// The radial r^8 term beyond every fitted model moves each ground-truth
// corner by exactly (fx x k4 r2^4, fy y k4 r2^4) (to rounding, 1e-9 px);
// and a thin prism held by the camera's own model (vision::Camera's s1..s4)
// renders the same corners as the same prism given to the renderer, so the
// truth and a calibration that fits it describe one lens.
TEST(Realism, RadialR8TermAndCameraThinPrismMoveTheCornersAsModelled) {
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::Target target = vision::Target::paper_default();
  sim::scene::SceneOptions r8 = noise_free();
  r8.radial_k4 = 0.4;
  const sim::scene::SceneRenderer plain(camera, target, vision::Codebook(), noise_free());
  const sim::scene::SceneRenderer bent(camera, target, vision::Codebook(), r8);
  const vision::Pose T = facing(0.25, {0.03, 0.02});
  const auto a = plain.render(T, 1), b = bent.render(T, 1);
  ASSERT_EQ(a.markers.size(), b.markers.size());
  const auto& k = camera.intrinsics();
  double largest = 0;
  for (size_t m = 0; m < a.markers.size(); ++m)
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector3d p = T * target.corners_m(target.markers[m])[c];
      const double x = p.x() / p.z(), y = p.y() / p.z(), r8_term = 0.4 * std::pow(x * x + y * y, 4);
      const Eigen::Vector2d expected(k.fx * x * r8_term, k.fy * y * r8_term);
      EXPECT_LT((b.markers[m].corners_px[c] - a.markers[m].corners_px[c] - expected).norm(), 1e-9);
      largest = std::max(largest, expected.norm());
    }
  ASSERT_GT(largest, 0.01);  // the comparison above sees the term

  vision::Distortion d = camera.distortion();
  d.s1 = 0.002;
  d.s3 = -0.0015;
  const vision::Camera prism_camera(camera.intrinsics(), d, camera.width_px(), camera.height_px());
  sim::scene::SceneOptions prism = noise_free();
  prism.thin_prism = {0.002, 0.0, -0.0015, 0.0};
  const auto in_camera =
      sim::scene::SceneRenderer(prism_camera, target, vision::Codebook(), noise_free())
          .render(T, 1);
  const auto in_options =
      sim::scene::SceneRenderer(camera, target, vision::Codebook(), prism).render(T, 1);
  ASSERT_EQ(in_camera.markers.size(), in_options.markers.size());
  for (size_t m = 0; m < in_camera.markers.size(); ++m)
    for (int c = 0; c < 4; ++c)
      EXPECT_LT((in_camera.markers[m].corners_px[c] - in_options.markers[m].corners_px[c]).norm(),
                1e-9);
}

// A sheet printed (1 + s) times too large at pose (R, t) projects exactly as
// the nominal sheet at (R, t / (1 + s)) (pinhole: scaling the scene about the
// camera centre leaves the image unchanged). A solver that believes the
// nominal size therefore reports d / (1 + s): too short by s d / (1 + s).
// Tolerance: the same solver on the unscaled sheet at the same pose is the
// reference, so its own bias cancels; what is left is the detector's corner
// error on two differently sampled noise-free images, ~0.02 px per corner,
// over the marker's side of >= 80 px: 0.02 sqrt(2) / 80 = 3.5e-4 of d; the
// bound is 2x that, 1/7 of the effect at s = 0.5 %.
TEST(Realism, PrintScaleErrorShortensEverySolversDistance) {
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::Target nominal = vision::Target::paper_default();
  constexpr double s = 0.005;
  const vision::Target printed = sim::camera::scaled_target(nominal, s);
  const sim::scene::SceneRenderer as_laid_out(camera, nominal, vision::Codebook(), noise_free());
  const sim::scene::SceneRenderer as_printed(camera, printed, vision::Codebook(), noise_free());
  const vision::FrameMeasurer measurer(camera, nominal);
  int compared = 0;
  for (double d : {0.25, 0.35, 0.45}) {
    const vision::Pose T = facing(d);
    const auto ref = measurer.measure(as_laid_out.render(T, 1).image);
    const auto got = measurer.measure(as_printed.render(T, 1).image);
    ASSERT_EQ(ref.primary().estimates.size(), got.primary().estimates.size()) << d;
    for (size_t i = 0; i < ref.primary().estimates.size(); ++i) {
      const vision::Estimate &e0 = ref.primary().estimates[i].estimate,
                             &e1 = got.primary().estimates[i].estimate;
      if (!e0.converged || !e1.converged) continue;
      EXPECT_NEAR(e1.distance_m / e0.distance_m * (1 + s), 1.0, 7e-4)
          << ref.primary().estimates[i].scope << " " << e0.solver << " at " << d << " m";
      ++compared;
    }
  }
  EXPECT_GE(compared, 3 * 10);  // every solver converged on both scopes at most distances
}

// Abbe error: the carriage pitching by theta about the guide's pivot moves
// the optical centre, h above it, by h theta along the travel (towards the
// target for a positive pitch about bench y) and turns the camera by theta;
// a yaw with the camera beside (y) or ahead of (x) the pivot moves it along
// x or y by the lever times the angle. First order in theta: the second-order
// rest, lever x theta^2 / 2 (1.3e-8 m for 120 mm and 96 arcsec), bounds the
// tolerance of 2e-8 m, against an effect of 5.6e-5 m.
TEST(Realism, CarriagePitchAndYawMoveTheCameraByLeverArmTimesAngle) {
  const vision::RigGeometry g = nominal_geometry();
  const auto centre_in_bench = [&g](const vision::Pose& T_cam_target) {
    return (g.T_bench_target * T_cam_target.inverse()).t;
  };
  constexpr double kArcsec = M_PI / (180.0 * 3600.0);
  const double x_mm = 600, y_mm = 150;
  sim::camera::CarriageAttitude pitch;
  pitch.x.pitch_arcsec_per_100mm = 10;  // 60 arcsec at 600 mm
  pitch.x.pitch_arcsec_per_100mm2 = 1;  // + 36 arcsec
  pitch.abbe_offset_mm = {0, 0, 120};
  const double theta = (60 + 36) * kArcsec;
  EXPECT_NEAR(pitch.x.pitch_rad(x_mm), theta, 1e-15);
  const vision::Pose flat = g.T_cam_target(x_mm, y_mm), turned = pitch.T_cam_target(g, x_mm, y_mm);
  const Eigen::Vector3d moved = centre_in_bench(turned) - centre_in_bench(flat);
  EXPECT_NEAR(moved.x(), 0.120 * theta, 2e-8);  // 55.8 um
  EXPECT_NEAR(moved.y(), 0, 2e-8);
  EXPECT_NEAR(moved.z(), 0, 2e-8);
  EXPECT_NEAR(vision::rotation_angle_between(flat.R, turned.R), theta, 1e-12);
  // The distance to the target (along +x) shrinks by the Abbe error.
  EXPECT_NEAR(flat.distance_m() - turned.distance_m(),
              0.120 * theta * (g.T_bench_target.t - centre_in_bench(flat)).normalized().x(), 2e-8);

  sim::camera::CarriageAttitude yaw;
  yaw.y.yaw_arcsec_per_100mm = 20;  // 30 arcsec at y = 150 mm
  yaw.abbe_offset_mm = {80, 50, 0};
  const double psi = 30 * kArcsec;
  const Eigen::Vector3d shift =
      centre_in_bench(yaw.T_cam_target(g, x_mm, y_mm)) - centre_in_bench(flat);
  EXPECT_NEAR(shift.x(), -0.050 * psi, 2e-8);  // w x lever = (0, 0, psi) x (80, 50, 0) mm
  EXPECT_NEAR(shift.y(), 0.080 * psi, 2e-8);
  EXPECT_NEAR(shift.z(), 0, 2e-8);

  // No angular error: exactly the geometry's pose.
  const sim::camera::CarriageAttitude none;
  EXPECT_TRUE(none.zero());
  EXPECT_EQ(none.T_cam_target(g, x_mm, y_mm).t, flat.t);
}

// The shipped profiles' new terms: ideal has none, lab and paper have each
// (the paper's rig the worse), and the sim rig's camera maps positions through
// the attitude while the bench (its encoders) never sees it.
TEST(Realism, ProfilesCarryGlareFlickerBowAndCarriageAttitude) {
  const sim::camera::RealismProfile ideal = shipped("ideal"), lab = shipped("lab"),
                                    paper = shipped("paper");
  const sim::scene::SceneOptions d;
  EXPECT_EQ(ideal.scene.glare_peak, 0);
  EXPECT_EQ(ideal.scene.flicker_modulation, 0);
  EXPECT_EQ(ideal.scene.bow_sag_m, 0);
  EXPECT_EQ(ideal.scene.ink_gloss, d.ink_gloss);
  EXPECT_TRUE(ideal.attitude.zero());
  for (const auto* p : {&lab, &paper}) {
    EXPECT_GT(p->scene.glare_peak, 0) << p->name;
    EXPECT_GT(p->scene.flicker_modulation, 0) << p->name;
    EXPECT_GT(p->scene.bow_sag_m, 0) << p->name;
    EXPECT_GT(p->scene.ink_gloss, p->scene.paper_gloss) << p->name;
    EXPECT_FALSE(p->attitude.zero()) << p->name;
    EXPECT_GT(p->attitude.abbe_offset_mm.norm(), 0) << p->name;
  }
  EXPECT_GT(paper.scene.bow_sag_m, lab.scene.bow_sag_m);
  EXPECT_EQ(paper.scene.bow_shape, sim::scene::SceneOptions::BowShape::kCylinderX);
  EXPECT_EQ(lab.attitude.abbe_offset_mm, Eigen::Vector3d(0, 0, 60));
  EXPECT_EQ(paper.attitude.x.pitch_arcsec_per_100mm, 10.0);
  EXPECT_EQ(lab.scene.flicker_frequency_hz, 120.0);
  EXPECT_NE(profile_error("[target]\nbow_shape = \"saddle\"\n")
                .find("target.bow_shape = \"saddle\": expected \"dome\", \"cylinder_x\" or "
                      "\"cylinder_y\""),
            std::string::npos);
  EXPECT_NE(profile_error("[bench]\nabbe_offset_mm = [0, 0]\n").find("bench.abbe_offset_mm"),
            std::string::npos);
  EXPECT_NE(profile_error("[light]\nflicker_modulation = 1.5\n")
                .find("light.flicker_modulation = 1.5: expected a number in 0 .. 1"),
            std::string::npos);
}

// Bow: a marker at sag h appears h closer. The pose marker sits at the
// sheet's centre, under the dome's apex; its corners, 25 mm out, carry
// h_c = sag (1 - (25/105)^2 / 2 - (25/148.5)^2 / 2) = 0.957 sag, so every
// solver's plane through them moves h_c towards the camera along the sheet's
// normal: |t - h_c n| - |t|. Noise-free renders, so both frames differ only by
// the bow; the corners' deterministic bias (~0.005 px on a ~150 px marker at
// 0.25-0.35 m: 0.01 mm of distance) is far inside 0.06 mm, while the effect is
// 1.9 mm.
TEST(Realism, BowBringsTheMarkerCloserByItsSag) {
  const vision::Camera camera = vision::Camera::paper_default();
  const vision::Target target = vision::Target::paper_default();
  sim::scene::SceneOptions bowed = noise_free();
  bowed.bow_sag_m = 0.002;
  const sim::scene::SceneRenderer flat(camera, target, vision::Codebook(), noise_free());
  const sim::scene::SceneRenderer bent(camera, target, vision::Codebook(), bowed);
  const vision::FrameMeasurer measurer(camera, target);
  const auto corners = target.corners_m(target.pose_marker_id);
  double h_c = 0;
  for (const auto& c : corners)
    h_c += sim::scene::sheet_sag_m(bowed, target, c.x(), c.y()) / 4;
  EXPECT_NEAR(h_c, 0.002 * 0.957, 2e-6);
  int compared = 0;
  for (double d : {0.25, 0.35}) {
    const vision::Pose T = facing(d);
    const double expected = (T.t - h_c * T.R.col(2)).norm() - T.t.norm();
    const auto ref = measurer.measure(flat.render(T, 1).image);
    const auto got = measurer.measure(bent.render(T, 1).image);
    ASSERT_EQ(ref.primary().estimates.size(), got.primary().estimates.size()) << d;
    for (size_t i = 0; i < ref.primary().estimates.size(); ++i) {
      if (ref.primary().estimates[i].scope != std::to_string(target.pose_marker_id)) continue;
      const vision::Estimate &e0 = ref.primary().estimates[i].estimate,
                             &e1 = got.primary().estimates[i].estimate;
      if (!e0.converged || !e1.converged) continue;
      EXPECT_NEAR(e1.distance_m - e0.distance_m, expected, 6e-5) << e0.solver << " at " << d;
      ++compared;
    }
  }
  EXPECT_GE(compared, 2 * 8);
}

}  // namespace
