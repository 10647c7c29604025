// rig report DB [--run ID] [--baseline DB[:RUN]] [--fail-on-regression]
//            [--geometry FILE [--calibration FILE]] --out DIR:
// the regression report of one run of a run database: report.html
// (self-contained, printable), report.json (every figure's numbers) and one
// CSV file per table, in DIR. With --geometry (and --calibration), the run's
// truth is recomputed from its stored read-backs under those files
// (report_truth.hpp) instead of the geometry and calibration it ran with.
//
// Exit codes: 0 written; 1 a failure while reading or writing; 2 bad input
// (missing file, not a rig database, newer or older schema, no completed run,
// no such run, --fail-on-regression without --baseline, --out naming an
// existing file); 3 with --fail-on-regression: written, and some solver got
// significantly worse than the baseline (for CI of products that depend on
// the solvers).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "db/report/report.hpp"
#include "db/store/saved_frame.hpp"
#include "db/store/store.hpp"
#include "report_truth.hpp"
#include "vision/detector_image.hpp"
#include "vision/image_codecs.hpp"

namespace rig::cli {
namespace {

struct ReportArgs {
  std::string database;
  std::optional<std::int64_t> run_id;
  std::string baseline;
  bool fail_on_regression = false;
  std::string out_dir;
  std::string geometry, calibration;
  db::report::ReportOptions options;
};

// Prints every figure the candidate run got significantly worse in than the
// baseline; returns how many.
std::size_t print_regressions(const db::report::Report& report) {
  std::size_t worse = 0;
  for (const db::report::ComparedFigure& f : report.comparison()) {
    if (!f.worse) continue;
    ++worse;
    std::cout << "worse: " << f.solver << " scope " << f.scope << ": " << f.figure << " "
              << f.candidate << " against " << f.baseline << " (z = " << f.difference.z << ")\n";
  }
  std::cout << (worse == 0 ? "no solver significantly worse than the baseline\n"
                           : std::to_string(worse) + " figure(s) significantly worse\n");
  return worse;
}

// Pictures are at most this wide (px): three fit side by side at 1400 px.
constexpr int kPictureWidth = 360;
// Okabe-Ito orange (BGR): visible on a grey frame and for colour-blind readers.
const cv::Scalar kDetectionColour(0, 159, 230);

// The saved frame's bytes, if the file is still there with the SHA-256 the
// run stored; else why not (for the report's log).
std::optional<std::string> saved_frame(const db::store::FrameRecord& f, std::string& why) {
  if (!f.image_path || !f.image_sha256) {
    why = "not saved";
    return std::nullopt;
  }
  try {
    return db::store::read_saved_frame(*f.image_path, *f.image_sha256);
  } catch (const db::store::SavedFrameError& e) {
    why = e.what();
    return std::nullopt;
  }
}

// One frame scaled to kPictureWidth at most, each detection's corners A-D
// (filled dots, joined) and its marker id drawn where the database says;
// nothing, with `why` set, when the bytes do not decode.
std::optional<db::report::FramePicture> draw_frame(const db::store::FrameRecord& f,
                                                   const std::string& bytes,
                                                   const db::report::FrameToShow& which,
                                                   std::string& why) {
  cv::Mat image;
  try {
    image = vision::decode_image(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(),
                                 cv::IMREAD_COLOR, *f.image_path);
  } catch (const vision::ImageError& e) {
    why = e.what();
    return std::nullopt;
  }
  const double scale = std::min(1.0, static_cast<double>(kPictureWidth) / image.cols);
  cv::Mat picture;
  cv::resize(image, picture, cv::Size(), scale, scale, cv::INTER_AREA);
  for (const db::store::DetectionRecord& d : f.detections) {
    std::vector<cv::Point> corners;
    for (int c = 0; c < 4; ++c)
      corners.emplace_back(static_cast<int>(std::lround(d.corners_px[2 * c] * scale)),
                           static_cast<int>(std::lround(d.corners_px[2 * c + 1] * scale)));
    cv::polylines(picture, corners, true, kDetectionColour, 1, cv::LINE_8);
    cv::putText(picture, std::to_string(d.marker_id), corners[0] + cv::Point(4, -4),
                cv::FONT_HERSHEY_SIMPLEX, 0.4, kDetectionColour, 1, cv::LINE_8);
  }
  for (const db::store::DetectionRecord& d : f.detections)  // dots last: on top of any label
    for (int c = 0; c < 4; ++c)
      cv::circle(picture,
                 cv::Point(static_cast<int>(std::lround(d.corners_px[2 * c] * scale)),
                           static_cast<int>(std::lround(d.corners_px[2 * c + 1] * scale))),
                 2, kDetectionColour, cv::FILLED, cv::LINE_8);
  std::vector<unsigned char> png;
  if (!vision::imencode(".png", picture, png)) return std::nullopt;
  db::report::FramePicture p;
  p.frame = which;
  p.png.assign(png.begin(), png.end());
  p.width = picture.cols;
  p.height = picture.rows;
  p.scale = scale;
  const std::size_t n = f.detections.size();
  const std::string detector = n > 0 ? f.detections.front().detector : "";
  p.drawn = std::to_string(n) + (n == 1 ? " marker" : " markers") + " detected" +
            (detector.empty() ? "" : " by " + detector) + ": corners A-D (dots) and ids in orange";
  return p;
}

// The pictures of the frames the report shows, from the frames the run
// saved; a frame that is not there is said once on stderr and left out.
std::vector<db::report::FramePicture> draw_pictures(const db::report::Report& report,
                                                    const std::string& database) {
  std::vector<db::report::FramePicture> out;
  const std::vector<db::report::FrameToShow> wanted = report.frames_to_show();
  if (wanted.empty()) return out;
  db::store::StoreOptions options;
  options.read_only = true;
  const db::store::Store store(database, options);
  std::size_t missing = 0;
  std::string why;
  for (const db::report::FrameToShow& w : wanted) {
    const db::store::PositionRecord p = store.position(report.study().run.id, w.plan_index);
    if (w.frame_index < 0 || static_cast<std::size_t>(w.frame_index) >= p.frames.size()) continue;
    // The run's primary detector's detections only (one outline per marker).
    db::store::FrameRecord f = p.frames[static_cast<std::size_t>(w.frame_index)];
    const std::string& primary = report.study().run.description.primary_detector;
    f.detections.erase(
        std::remove_if(f.detections.begin(), f.detections.end(),
                       [&](const db::store::DetectionRecord& d) { return d.detector != primary; }),
        f.detections.end());
    std::string reason;
    const std::optional<std::string> bytes = saved_frame(f, reason);
    std::optional<db::report::FramePicture> picture;
    if (bytes) picture = draw_frame(f, *bytes, w, reason);
    if (!bytes || !picture) {
      ++missing;
      why = reason;
      continue;
    }
    out.push_back(std::move(*picture));
  }
  if (missing > 0 && !(missing == wanted.size() && why == "not saved"))
    std::cerr << "rig report: " << missing << " of " << wanted.size()
              << " frames to show left out, e.g. " << why << "\n";
  return out;
}

// Refuses arguments that cannot give what was asked before any work.
void check_report_args(const ReportArgs& a) {
  if (a.fail_on_regression && a.baseline.empty())
    throw BadInput(
        "--fail-on-regression without --baseline: a regression is a comparison with a "
        "baseline; expected --baseline DB or DB:RUN");
  if (!a.calibration.empty() && a.geometry.empty())
    throw BadInput("--calibration " + a.calibration +
                   " without --geometry: the truth is recomputed under a new rig geometry; "
                   "expected --geometry FILE (e.g. the rig.toml rig calibrate wrote) with it");
  std::error_code ec;
  if (std::filesystem::exists(a.out_dir, ec) && !std::filesystem::is_directory(a.out_dir, ec))
    throw BadInput("--out " + a.out_dir +
                   ": is an existing file, not a directory; expected a directory (created if "
                   "missing) for report.html, report.json and the CSV tables");
}

int run_report(const ReportArgs& a) {
  check_report_args(a);
  db::report::ReportOptions options = a.options;
  options.run_id = a.run_id;
  if (!a.geometry.empty()) {
    TruthFiles files{a.geometry, std::nullopt};
    if (!a.calibration.empty()) files.calibration = a.calibration;
    options.recompute_truth = [files](const db::store::Run& run,
                                      const std::vector<db::store::PositionRecord>& positions) {
      return recompute_truth(files, run, positions);
    };
  }
  std::optional<db::report::RunReference> baseline;
  if (!a.baseline.empty()) baseline = db::report::RunReference::parse(a.baseline);
  db::report::Report report(a.database, options, baseline);
  report.set_pictures(draw_pictures(report, a.database));
  const db::report::ReportFiles files = report.write(a.out_dir);
  const db::report::RunStudy& s = report.study();
  std::cout << "run " << s.run.id << " of " << a.database << ": " << s.positions << " positions, "
            << s.estimates << " estimates\n"
            << files.html << "\n"
            << files.json << "\n"
            << files.csv.size() << " CSV tables in " << a.out_dir << "\n";
  if (report.baseline() && print_regressions(report) > 0 && a.fail_on_regression)
    return kExitRegression;
  return kExitOk;
}

}  // namespace

void add_report_command(CLI::App& app, ExitStatus& status) {
  auto args = std::make_shared<ReportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "report",
      "Regression report of a run: HTML with SVG figures, JSON and CSV (paper Tables 2-6, "
      "Figs. 8-12, and beyond)");
  cmd->add_option("DB", args->database, "Run database written by rig sweep")->required();
  cmd->add_option("--run", args->run_id, "Run id (default: the latest completed run)");
  cmd->add_option("--baseline", args->baseline,
                  "Compare with this run: DB or DB:RUN (default run: its latest completed one)");
  cmd->add_flag("--fail-on-regression", args->fail_on_regression,
                "Exit with 3 when a solver got significantly worse than the baseline");
  cmd->add_option("--out", args->out_dir, "Output directory (created if missing)")->required();
  cmd->add_option("--geometry", args->geometry,
                  "Recompute the run's truth (distance, viewing angle, bounds) from its stored "
                  "read-backs under this rig geometry file, e.g. rig calibrate's rig.toml");
  cmd->add_option("--calibration", args->calibration,
                  "With --geometry: the camera calibration of the recomputed truth (default: the "
                  "run's stored one)");
  cmd->add_option("--ambiguity-threshold", args->options.ambiguity_ratio_threshold,
                  "Ambiguity ratio (better/worse planar solution error) from which an "
                  "estimate counts as ambiguous")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--flip-angle", args->options.flip_angle_deg,
                  "Pose-marker vs whole-target rotation difference that counts as a flip, deg")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 180.0));
  cmd->add_option(
         "--true-distance-sd", args->options.true_distance_sd_m,
         "Random error of the true distance (bench read-back repeatability) for the Deming "
         "regression, m")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--k", args->options.significance_k,
                  "Differences are significant beyond k standard errors")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->footer(
      "Exit codes: 0 written, 1 failure, 2 bad input, 3 regression (with --fail-on-regression).\n"
      "Example: rig report runs.db --out report/\n"
      "         rig report runs.db --run 7 --baseline main.db:3 --fail-on-regression --out "
      "report/\n"
      "         rig report runs.db --geometry calibrated/rig.toml --calibration "
      "calibrated/camera.yaml --out report/");
  cmd->callback(
      [&status, args] { status.code = run_command("report", [&] { return run_report(*args); }); });
}

}  // namespace rig::cli
