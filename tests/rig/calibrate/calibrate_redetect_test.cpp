// `rig calibrate` on a run that saved its frames: the second pass detects
// them again through the first pass's camera (rig::calibrate::redetected),
// the files it writes say so, a frame that changed since the run is refused
// naming the file, and --redetect yes on a run without frames is refused.
// The run: a calibration sweep of the simulated lab rig (truth seed 3, every
// fourth plan position, one frame each), its frames as PNG files with their
// SHA-256 and its detections in a real run database
// (tests/rig/calibrate/sim_truth_calibration.hpp).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "rig_command.hpp"
#include "sim_truth_calibration.hpp"
#include "store_fixture.hpp"
#include "synthetic_calibration.hpp"

namespace {

rig_test::SimTruthSweep sweep_of_seed_3() {
  rig_test::SimTruthSweepSpec spec;
  spec.source_dir = RIG_SOURCE_DIR;
  spec.truth_seed = 3;
  spec.bow_sag_mm = 0.0;
  spec.position_stride = 4;
  return rig_test::render_calibration_sweep(spec);
}

nlohmann::json calibration_json(const std::string& out) {
  std::ifstream in(out + "/calibration.json");
  return nlohmann::json::parse(in);
}

double fx_of(const nlohmann::json& j) {
  for (const nlohmann::json& p : j["parameters"])
    if (p["name"] == "fx") return p["value"].get<double>();
  return 0;
}

TEST(CalibrateRedetect, SavedFramesAreDetectedAgainThroughTheFirstPassCamera) {
  const db_test::ScratchDir dir;
  const rig_test::SimTruthSweep sweep = sweep_of_seed_3();
  std::filesystem::create_directory(dir.file("frames"));
  rig_test::write_sim_truth_run(sweep, RIG_SOURCE_DIR, dir.file("run.db"), dir.file("frames"));
  const std::size_t frames = sweep.images.size();

  const rig_test::RigRun two =
      rig_test::run_rig("calibrate " + dir.file("run.db") + " --out " + dir.file("two"));
  ASSERT_EQ(two.exit_code, 0) << two.err;
  EXPECT_NE(two.out.find("detecting the " + std::to_string(frames) + " saved frames again"),
            std::string::npos)
      << two.out;
  const nlohmann::json j = calibration_json(dir.file("two"));
  EXPECT_NE(j["corners_from"].get<std::string>().find(std::to_string(frames) +
                                                      " saved frames, detected again by rig"),
            std::string::npos)
      << j["corners_from"];
  // 56 positions are fewer than 3 per free parameter (21): the standard
  // deviations take the corners as independent, and say so.
  EXPECT_EQ(j["sd_method"], "independent corners (56 positions: too few to cluster)");
  // The same two passes in process on the same images (PNG is lossless, so
  // the detections are the same bits): the same fx to the solver's own
  // tolerance (function_tolerance 1e-12 moves fx by far less than 1e-6).
  const rig::calibrate::CalibrationOptions options;
  const rig::calibrate::CalibrationResult first = rig::calibrate::calibrate(sweep.problem, options);
  const rig::calibrate::CalibrationResult second =
      rig::calibrate::calibrate(rig_test::redetected(sweep, first.camera), options);
  EXPECT_NEAR(fx_of(j), second.camera.intrinsics().fx, 1e-6 * second.camera.intrinsics().fx);

  const rig_test::RigRun one = rig_test::run_rig("calibrate " + dir.file("run.db") +
                                                 " --redetect no --out " + dir.file("one"));
  ASSERT_EQ(one.exit_code, 0) << one.err;
  EXPECT_EQ(calibration_json(dir.file("one"))["corners_from"], "the run's detections");
  EXPECT_NEAR(fx_of(calibration_json(dir.file("one"))), first.camera.intrinsics().fx,
              1e-6 * first.camera.intrinsics().fx);

  // A saved frame changed since the run: refused, naming it; nothing written.
  const std::string frame = dir.file("frames") + "/p8_f0.png";
  ASSERT_TRUE(std::filesystem::exists(frame));
  std::fstream(frame, std::ios::in | std::ios::out | std::ios::binary).seekp(100).put('\x5a');
  const rig_test::RigRun changed =
      rig_test::run_rig("calibrate " + dir.file("run.db") + " --out " + dir.file("changed"));
  EXPECT_EQ(changed.exit_code, 2);
  EXPECT_NE(changed.err.find("recorded frame " + frame + " has SHA-256"), std::string::npos)
      << changed.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("changed")));
}

TEST(CalibrateRedetect, RedetectYesOnARunWithoutFramesIsRefused) {
  const db_test::ScratchDir dir;
  rig_test::SyntheticCalibrationSpec spec;
  spec.true_camera = rig_test::calibration_true_camera();
  spec.true_geometry = rig_test::calibration_true_geometry();
  spec.nominal_rig_toml = rig_test::calibration_nominal_rig_toml();
  spec.plan = rig_test::read_csv_plan(rig_test::calibration_plan_path(RIG_SOURCE_DIR));
  spec.target_layout_path = rig_test::calibration_target_path(RIG_SOURCE_DIR);
  rig_test::write_calibration_run(dir.file("run.db"), spec);
  const rig_test::RigRun r = rig_test::run_rig("calibrate " + dir.file("run.db") +
                                               " --redetect yes --out " + dir.file("out"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(dir.file("run.db") + ":1: the run saved no frames ([capture] save_frames)"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("out")));
  // auto: the run's detections, as before; 221 positions are enough to
  // cluster the standard deviations by position.
  const rig_test::RigRun a =
      rig_test::run_rig("calibrate " + dir.file("run.db") + " --out " + dir.file("auto"));
  ASSERT_EQ(a.exit_code, 0) << a.err;
  EXPECT_NE(a.out.find(": one pass, on the run's detections: the run saved no frames"),
            std::string::npos)
      << a.out;
  const nlohmann::json j = calibration_json(dir.file("auto"));
  EXPECT_EQ(j["corners_from"], "the run's detections");
  EXPECT_EQ(j["sd_method"], "clustered by bench position (221 positions)");
}

}  // namespace
