// rig::calibrate: the bench calibrates its own camera and rig geometry.
//
// A translation stage with known displacements turns the planar target into
// a 3D calibration object (Tsai 1987, "A versatile camera calibration
// technique for high-accuracy 3D machine vision metrology using off-the-shelf
// TV cameras and lenses", IEEE J. Robotics and Automation 3(4)). One joint
// bundle adjustment (Ceres, Huber loss) over every detected corner of every
// frame of a calibration sweep estimates at once:
//   - the intrinsics fx, fy, cx, cy (px) and distortion k1, k2, p1, p2, k3
//     and (DistortionModel::kThinPrism) the thin prism s1..s4 (Weng, Cohen &
//     Herniou 1992; vision/camera.hpp), each fixable;
//   - the camera rotation relative to the bench axes, R_bench_cam =
//     R_nominal * Rot(misalignment) (rotation vector, degrees, about the
//     nominal camera axes as in a rig file, docs/frames.md);
//   - the target orientation in the bench frame, R_bench_target =
//     R_nominal * Rot(tilt);
//   - the camera-to-target offset at bench zero, d = t_bench_target -
//     t_carriage_cam (bench axes, metres in the API, mm in files);
//   - the sheet's print scale error s: printers and paper scale a print by
//     0.1-0.5 %, and the bench's read-backs are a length standard the layout
//     is not, so the sheet as printed is (1 + s) times its layout (fixable).
// Knowns: the bench read-backs (positions.measured_x_mm / measured_y_mm) and
// the target layout. A corner P (target frame, as laid out) seen with the
// carriage at (x, y) mm projects through the camera model from
//   p_cam = R_bench_cam^T (R_bench_target (1 + s) P + d - (x, y, 0) / 1000).
// With translation-only motion the camera's offset on the carriage and the
// target's origin enter only through their difference d: the output keeps the
// camera offset of the nominal rig geometry and puts the target origin at
// offset + d (docs/calibration.md).
//
// Observability (check_observable): the plan must move the camera both
// towards the target (bench x) and across it (bench y). With one bench
// distance the focal lengths trade against the target distance (a planar
// target at one depth); with one row (no y motion) the rotation about the
// bench x axis trades against the target's tilt, with one column (no x
// motion) the rotation about bench y as well. After the solve, the Jacobian
// at the solution (columns scaled to unit norm) must have full rank: its
// smallest singular value over its largest at least kMinRelativeSingularValue,
// else the parameter with the largest share of the weakest direction is named.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "vision/camera.hpp"
#include "vision/detectors.hpp"
#include "vision/rig_geometry.hpp"
#include "vision/target.hpp"

namespace rig::calibrate {

// A run database, run or its contents that cannot be calibrated from: no such
// file or run, no detections, a bad stored file. The message names the input.
// Bad input (exit 2).
class CalibrationInputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The plan cannot separate two parameters; the message names them and why.
class UnobservablePlan : public CalibrationInputError {
 public:
  using CalibrationInputError::CalibrationInputError;
};

// One detected marker corner: what the bundle adjustment fits.
struct CornerObservation {
  std::int64_t plan_index = 0;
  double x_mm = 0, y_mm = 0;  // bench read-back, mm
  int marker_id = 0;
  int corner = 0;                                            // 0..3 = A..D
  Eigen::Vector3d target_point_m = Eigen::Vector3d::Zero();  // target frame, m
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();           // distorted px
};

// A frame of the calibration sweep that the run saved ([capture]
// save_frames): where the bench stood and the file, whose SHA-256 is checked
// when it is read.
struct CalibrationFrame {
  std::int64_t plan_index = 0;
  double x_mm = 0, y_mm = 0;  // bench read-back, mm
  std::string image_path, image_sha256;
};

// What a calibration starts from: the nominal camera and geometry (starting
// values; the geometry's camera offset is kept) and the observations.
struct CalibrationProblem {
  std::string source;  // "run.db:3", for messages
  vision::Camera nominal_camera = vision::Camera::paper_default();
  vision::RigGeometry nominal_geometry;
  vision::Target target = vision::Target::paper_default();
  std::vector<CornerObservation> corners;
  // Where the corners come from, for calibration.json.
  std::string corners_from = "the run's detections";
  // The detector that found them (a registry name, vision/detectors.hpp) and
  // the frames it found them in, when the run saved them (else empty).
  std::string detector = "rig";
  std::vector<CalibrationFrame> frames;
};

// Reads run `run_id` (default: the latest run with detections) of the run
// database at db_path: every detection of the run's primary detector in
// every frame of every ok position with a read-back, those frames' saved
// files (when the run saved them), and the stored calibration, layout and
// rig geometry
// (empty calibration or layout: the built-in defaults). Throws
// CalibrationInputError naming the file and run when the file is missing or
// not a run database, the run does not exist, or it has no detections of
// layout markers; the stored files' own errors (vision::CalibrationError,
// config::ConfigError) name the stored file.
CalibrationProblem read_run(const std::string& db_path, std::optional<std::int64_t> run_id);

// The corners of the layout's markers that `detector` finds in `image`, the
// saved frame `frame`. Throws std::invalid_argument for an image type the
// detector cannot convert.
std::vector<CornerObservation> detect_corners(const vision::FiducialDetector& detector,
                                              const vision::Target& target,
                                              const CalibrationFrame& frame, const cv::Mat& image);

// Throws CalibrationInputError naming the run when it saved no frames
// (problem.frames empty): its corners cannot be detected again.
void check_saved_frames(const CalibrationProblem& problem);

// The problem with its corners detected again in its saved frames, by its
// detector, through `camera` (a first calibration's). A detector that
// follows the lens (rig's: its edges are straight lines through the
// undistorted image) puts the corners where the lens model it is given says:
// with the nominal lens the corners of every position carry that model's
// error, and the calibration carries it on (on the simulated lab rig, fx's
// spread over ten truths fell from 6.4e-6 to 1.7e-6 when detected again,
// docs/calibration.md). Throws CalibrationInputError naming the run when it
// saved no frames, and naming the file when a frame cannot be read, changed
// since the run (SHA-256) or does not decode. The frames are read and
// detected on `threads` threads (1-64); the corners come in frame order.
CalibrationProblem redetected(const CalibrationProblem& problem, const vision::Camera& camera,
                              int threads = 2);

// The parameters, in this order (names as in calibration.json).
constexpr int kParameterCount = 23;
constexpr int kIntrinsicCount = 13;  // the first 13: fx fy cx cy k1 k2 p1 p2 k3 s1 s2 s3 s4
extern const std::array<const char*, kParameterCount> kParameterNames;
extern const std::array<const char*, kParameterCount> kParameterUnits;
// Index in kParameterNames of `name`; -1 when there is none.
int parameter_index(const std::string& name);

// The lens model the bundle adjustment fits: Brown-Conrady's 5 coefficients
// (k1 k2 p1 p2 k3; s1..s4 held at their nominal values), or those and the
// thin prism s1..s4 (OpenCV's 12-coefficient model with k4..k6 = 0). The thin
// prism is a tilt of a lens element or of the sensor (Weng et al. 1992); left
// out, its image shift biases the camera's pitch and yaw and the principal
// point (docs/calibration.md).
enum class DistortionModel { kBrownConrady5, kThinPrism };

struct CalibrationOptions {
  // Parameters held at their nominal values, by name: an intrinsic ("k3",
  // "s2") or "target_scale_error" (held at 0: the sheet is exactly its layout).
  std::vector<std::string> fixed;
  DistortionModel distortion = DistortionModel::kBrownConrady5;
  double huber_px = 1.0;  // robust loss scale, px of corner error
  int threads = 2;        // Ceres threads
  int max_iterations = 100;
  bool covariance = true;  // compute standard deviations and correlations
};

// Smallest relative singular value of the scaled Jacobian for a full-rank
// (observable) problem.
constexpr double kMinRelativeSingularValue = 1e-9;

struct ParameterEstimate {
  std::string name, unit;
  double value = 0;
  // Standard deviation (CalibrationResult::sd_method); 0 for a fixed parameter.
  double sd = 0;
  // What it would be if every corner coordinate erred independently by
  // sigma_px: sigma_px^2 (J^T J)^-1.
  double sd_independent = 0;
  bool fixed = false;
};

struct CalibrationResult {
  vision::Camera camera = vision::Camera::paper_default();
  vision::RigGeometry geometry;  // camera offset: nominal; target origin: offset + d
  // The calibration sheet as printed is (1 + this) times its layout
  // (parameter "target_scale_error"); a property of that print, not of the
  // camera or the rig: calibration.json reports it, no output file carries it.
  double target_scale_error = 0;
  std::array<ParameterEstimate, kParameterCount> parameters;
  // Correlations of the free parameters (kParameterCount x kParameterCount;
  // rows and columns of fixed parameters are 0, their diagonal 1).
  Eigen::MatrixXd correlation;
  // How the covariance behind sd and correlation was estimated, from the
  // Jacobian J and the residuals r at the solution: "clustered by bench
  // position (N positions)", the sandwich (J^T J)^-1 M (J^T J)^-1 with M the
  // sum over positions of their scores' outer products, which holds when the
  // corner errors of a position are correlated (they are: the detector's bias
  // under that position's blur and light, what the lens model leaves there);
  // or, with fewer than 3 positions per free parameter, "independent corners"
  // (sigma_px^2 (J^T J)^-1). docs/calibration.md compares both with the
  // spread over simulated truths.
  std::string sd_method;
  // Residual scale: sqrt(sum r^2 / (2 corners - free parameters)), px per
  // coordinate.
  double sigma_px = 0;
  double rms_px = 0;  // RMS corner error |r|, px
  std::map<std::int64_t, double> rms_by_position_px;
  std::map<int, double> rms_by_marker_px;
  std::size_t corners = 0;
  int iterations = 0;
  double solve_seconds = 0;
  std::string termination;  // Ceres's report line
};

// Refuses a plan that cannot separate the parameters (rule above): throws
// UnobservablePlan naming the parameters. Precondition: problem.corners not empty.
void check_observable(const CalibrationProblem& problem);

// Runs check_observable, then the bundle adjustment from the nominal values,
// then the rank check and (options.covariance) the covariance. Throws
// UnobservablePlan, CalibrationInputError for an unknown fixed name, and
// std::runtime_error when Ceres fails.
CalibrationResult calibrate(const CalibrationProblem& problem, const CalibrationOptions& options);

// RMS corner error |r| in px of the observations at the given plan indices
// (all when empty) predicted from bench read-backs through camera and
// geometry, the sheet printed at (1 + target_scale_error) times its layout.
double reprojection_rms_px(const CalibrationProblem& problem, const vision::Camera& camera,
                           const vision::RigGeometry& geometry,
                           const std::vector<std::int64_t>& plan_indices = {},
                           double target_scale_error = 0);

// Calibrates on the even plan indices and predicts the odd ones.
struct HeldOutCheck {
  std::size_t fit_positions = 0, held_out_positions = 0;
  double fit_rms_px = 0, held_out_rms_px = 0;
};
HeldOutCheck held_out_check(const CalibrationProblem& problem, CalibrationOptions options);

// The observations whose plan index is even (even = true) or odd.
CalibrationProblem alternate_positions(const CalibrationProblem& problem, bool even);

// Files written into out_dir (created if missing).
struct CalibrationFiles {
  std::string opencv, ros, rig, json;
};
// Writes camera.yaml (OpenCV FileStorage, vision::Camera::load reads it),
// camera_info.yaml (ROS camera_info), rig.toml (a rig geometry file) and
// calibration.json (every parameter with its standard deviation, the
// correlation matrix, residual RMS per position and per marker, the held-out
// check). Throws std::runtime_error naming a file that cannot be written.
CalibrationFiles write_calibration(const std::string& out_dir, const CalibrationProblem& problem,
                                   const CalibrationResult& result, const HeldOutCheck& held_out);

}  // namespace rig::calibrate
