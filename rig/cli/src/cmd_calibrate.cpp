// rig calibrate RUN.db[:RUN] --out DIR: the joint bundle adjustment of a
// calibration sweep (rig/calibrate/calibration.hpp): the calibrated camera
// (OpenCV FileStorage and ROS camera_info), the rig geometry file and
// calibration.json (values, standard deviations, correlations, residuals per
// position and marker, the held-out check), in DIR. When the run saved its
// frames, a second pass detects them again through the first pass's camera
// and calibrates from those corners (--redetect).
//
// Exit codes: 0 written; 1 a failure while solving or writing; 2 bad input
// (missing file, not a rig database, no such run, no detections, an
// unobservable plan, an unknown --fix name or --distortion model, --redetect
// yes on a run that saved no frames, a saved frame missing or changed).
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "commands.hpp"
#include "rig/calibrate/calibration.hpp"

namespace rig::cli {
namespace {

struct CalibrateArgs {
  std::string database;
  std::string out_dir;
  std::vector<std::string> fixed;
  std::string distortion = "5";
  double huber_px = 1.0;
  int threads = 2;
  std::string redetect = "auto";
};

// "runs.db:3" -> ("runs.db", 3); "runs.db" -> ("runs.db", none).
std::pair<std::string, std::optional<std::int64_t>> split_run(const std::string& text) {
  const std::size_t colon = text.rfind(':');
  if (colon == std::string::npos || colon + 1 == text.size()) return {text, std::nullopt};
  const std::string run = text.substr(colon + 1);
  if (run.find_first_not_of("0123456789") != std::string::npos) return {text, std::nullopt};
  return {text.substr(0, colon), std::stoll(run)};
}

int run_calibrate(const CalibrateArgs& a) {
  const auto [path, run] = split_run(a.database);
  calibrate::CalibrationProblem problem = calibrate::read_run(path, run);
  calibrate::CalibrationOptions options;
  options.fixed = a.fixed;
  options.distortion = a.distortion == "5" ? calibrate::DistortionModel::kBrownConrady5
                                           : calibrate::DistortionModel::kThinPrism;
  options.huber_px = a.huber_px;
  options.threads = a.threads;
  if (a.redetect == "yes") calibrate::check_saved_frames(problem);
  const bool two_passes = a.redetect == "yes" || (a.redetect == "auto" && !problem.frames.empty());
  if (two_passes) {
    // The first pass only gives the camera to detect through: no covariance.
    calibrate::CalibrationOptions first_options = options;
    first_options.covariance = false;
    const calibrate::CalibrationResult first = calibrate::calibrate(problem, first_options);
    std::cout << problem.source << ": first pass on the run's detections, " << first.corners
              << " corners, RMS " << std::setprecision(3) << first.rms_px << " px; detecting the "
              << problem.frames.size() << " saved frames again through its camera\n";
    problem = calibrate::redetected(problem, first.camera, a.threads);
  } else if (a.redetect == "auto") {
    std::cout << problem.source
              << ": one pass, on the run's detections: the run saved no frames to detect again "
                 "through the calibrated camera ([capture] save_frames in the sweep file gives "
                 "the second pass, docs/calibration.md)\n";
  }
  const calibrate::CalibrationResult result = calibrate::calibrate(problem, options);
  const calibrate::HeldOutCheck held_out = calibrate::held_out_check(problem, options);
  const calibrate::CalibrationFiles files =
      calibrate::write_calibration(a.out_dir, problem, result, held_out);
  std::cout << problem.source << ": " << result.corners << " corners, " << result.iterations
            << " iterations, " << std::setprecision(3) << result.solve_seconds << " s, RMS "
            << result.rms_px << " px; held out (odd positions): " << held_out.held_out_rms_px
            << " px\n";
  for (const calibrate::ParameterEstimate& e : result.parameters)
    std::cout << "  " << std::left << std::setw(28) << e.name << std::setprecision(8) << e.value
              << (e.fixed ? " (fixed)" : " +- ") << std::setprecision(3) << (e.fixed ? 0.0 : e.sd)
              << " " << e.unit << "\n";
  std::cout << files.opencv << "\n" << files.ros << "\n" << files.rig << "\n" << files.json << "\n";
  return kExitOk;
}

}  // namespace

void add_calibrate_command(CLI::App& app, ExitStatus& status) {
  auto args = std::make_shared<CalibrateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate",
      "Calibrate the camera and the rig geometry from a calibration sweep (joint bundle "
      "adjustment over every corner, bench read-backs as known displacements)");
  cmd->add_option("DB", args->database, "Run database written by rig sweep, DB or DB:RUN")
      ->required();
  cmd->add_option("--out", args->out_dir, "Output directory (created if missing)")->required();
  cmd->add_option(
      "--fix", args->fixed,
      "Hold a parameter at its nominal value: fx fy cx cy k1 k2 p1 p2 k3 s1 s2 s3 s4, or "
      "target_scale_error (the sheet printed exactly at its layout's size) "
      "(repeatable)");
  cmd->add_option("--distortion", args->distortion,
                  "Lens model to fit: 5 (Brown-Conrady k1 k2 p1 p2 k3; s1..s4 held at the "
                  "nominal calibration's values) or thin_prism (also s1..s4, OpenCV's "
                  "12-coefficient model with k4..k6 = 0)")
      ->capture_default_str()
      ->check(CLI::IsMember({"5", "thin_prism"}));
  cmd->add_option("--huber-px", args->huber_px, "Robust loss scale, px")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--redetect", args->redetect,
                  "Detect the corners again through the first pass's camera and calibrate from "
                  "them: auto (when the run saved its frames, [capture] save_frames), yes (it "
                  "must have), no (the run's detections only)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "yes", "no"}));
  cmd->add_option("--threads", args->threads, "Solver and detection threads")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  cmd->footer(
      "Exit codes: 0 written, 1 failure, 2 bad input (also an unobservable plan).\n"
      "Example: rig calibrate calibration.db --out calibrated/\n"
      "         rig calibrate runs.db:4 --fix k3 --out calibrated/");
  cmd->callback([&status, args] {
    status.code = run_command("calibrate", [&] { return run_calibrate(*args); });
  });
}

}  // namespace rig::cli
