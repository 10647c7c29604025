// rig detect IMAGE...: the fiducials in each image, and every pose solver's
// estimate from them, on the pose marker alone and on the whole target.
//
// --json prints one JSON object per image, one per line (a single image gives
// a single JSON document). Its shape is public:
//   {"image": PATH,
//    "detections": [{"id", "rotation", "corners": [[x, y] x 4], "quality":
//                    {"contrast", "bits_corrected", "edge_fit_residual_px"}}],
//    "estimates": [{"solver", "scope", "R", "t", "distance_m",
//                   "reprojection_error_px", "converged", "ambiguity_ratio", ...}]}
// Corners are distorted pixels in OpenCV's convention (pixel centres at
// integer coordinates), in the order A, B, C, D of the target layout. "scope"
// is the pose marker's id (its four corners alone) or "target" (every
// detected marker of the layout, the pose marker's corners first). R and t
// are T_cam_target (metres); "ambiguity_ratio" is null where a solver does
// not define it. An image that cannot be used gives {"image", "error",
// "detections": [], "estimates": []}.
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "estimate_json.hpp"
#include "vision/detector.hpp"
#include "vision/detector_image.hpp"
#include "vision/solvers.hpp"
#include "vision/target.hpp"

namespace rig {
namespace {

struct Options {
  std::vector<std::string> images;
  std::string camera_file;
  std::string target_file;
  bool json = false;
};

// One scope's estimates: the correspondences of `markers` (pose marker first)
// through every solver.
struct ScopeResult {
  nlohmann::json scope;
  std::vector<vision::Estimate> estimates;
  std::string error;  // correspondences the solvers cannot take
};

ScopeResult solve_scope(const nlohmann::json& scope,
                        const std::vector<const vision::Detection*>& markers,
                        const vision::Camera& camera, const vision::Target& target,
                        const std::vector<std::unique_ptr<vision::PoseSolver>>& solvers) {
  ScopeResult r{scope, {}, ""};
  std::vector<Eigen::Vector3d> object_points;
  std::vector<Eigen::Vector2d> image_points;
  for (const auto* d : markers) {
    const auto corners = target.corners_m(d->id);
    for (int k = 0; k < 4; ++k) {
      object_points.push_back(corners[k]);
      image_points.push_back(d->corners_px[k]);
    }
  }
  try {
    const vision::Correspondences c =
        vision::make_correspondences(camera, object_points, image_points);
    for (const auto& solver : solvers)
      r.estimates.push_back(solver->solve(c));
  } catch (const vision::InputError& e) {
    r.error = e.what();
  }
  return r;
}

nlohmann::json detection_to_json(const vision::Detection& d) {
  nlohmann::json corners = nlohmann::json::array();
  for (const auto& c : d.corners_px)
    corners.push_back({c.x(), c.y()});
  return {{"id", d.id},
          {"rotation", d.rotation},
          {"corners", corners},
          {"quality",
           {{"contrast", d.quality.contrast},
            {"bits_corrected", d.quality.bits_corrected},
            {"edge_fit_residual_px", d.quality.edge_fit_residual_px}}}};
}

void print_text(const std::string& image, const std::vector<vision::Detection>& detections,
                const std::vector<ScopeResult>& scopes) {
  std::printf("%s: %zu marker%s\n", image.c_str(), detections.size(),
              detections.size() == 1 ? "" : "s");
  for (const auto& d : detections) {
    std::printf("  id %2d rot %d  corners", d.id, d.rotation);
    for (const auto& c : d.corners_px)
      std::printf(" (%.3f, %.3f)", c.x(), c.y());
    std::printf("  contrast %.0f  bits corrected %d  edge residual %.3f px\n", d.quality.contrast,
                d.quality.bits_corrected, d.quality.edge_fit_residual_px);
  }
  for (const auto& s : scopes) {
    const std::string scope = s.scope.is_string() ? s.scope.get<std::string>()
                                                  : "marker " + std::to_string(s.scope.get<int>());
    if (!s.error.empty()) {
      std::printf("  %s: no estimate: %s\n", scope.c_str(), s.error.c_str());
      continue;
    }
    std::printf("  %s:\n  %-20s %-9s %11s %10s %9s %9s\n", scope.c_str(), "solver", "converged",
                "distance_m", "reproj_px", "time_us", "ambiguity");
    for (const auto& e : s.estimates) {
      if (!e.applicable()) {
        std::printf("  %-20s skipped: %s\n", e.solver.c_str(), e.message.c_str());
        continue;
      }
      const std::string ambiguity =
          e.ambiguity_ratio ? std::to_string(*e.ambiguity_ratio).substr(0, 6) : "-";
      std::printf("  %-20s %-9s %11.6f %10.4f %9.1f %9s\n", e.solver.c_str(),
                  e.converged ? "yes" : "no", e.distance_m, e.reprojection_error_px, e.time_us,
                  ambiguity.c_str());
    }
  }
}

// Returns false when the image could not be used (the error is printed).
bool detect_one(const std::string& path, const vision::Detector& detector,
                const vision::Target& target,
                const std::vector<std::unique_ptr<vision::PoseSolver>>& solvers, bool json) {
  std::vector<vision::Detection> detections;
  std::string error;
  try {
    const cv::Mat image = vision::read_image(path);
    const auto& camera = detector.camera();
    if (image.cols != camera.width_px() || image.rows != camera.height_px())
      throw vision::ImageError(
          "image '" + path + "': is " + std::to_string(image.cols) + "x" +
          std::to_string(image.rows) + " px but the camera calibration is for " +
          std::to_string(camera.width_px()) + "x" + std::to_string(camera.height_px()) + " px");
    detections = detector.detect(image);
  } catch (const vision::ImageError& e) {
    error = e.what();
  } catch (const std::invalid_argument& e) {  // an image type the detector cannot convert
    error = "image '" + path + "': " + e.what();
  }
  if (!error.empty()) {
    std::cerr << "rig detect: " << error << "\n";
    if (json)
      std::cout << nlohmann::json{{"image", path},
                                  {"error", error},
                                  {"detections", nlohmann::json::array()},
                                  {"estimates", nlohmann::json::array()}}
                       .dump()
                << std::endl;
    return false;
  }

  // The layout's markers, each id once (a second sighting of an id would make
  // the correspondences ambiguous; it is reported, not used).
  const vision::Detection* pose_marker = nullptr;
  std::vector<const vision::Detection*> others;
  for (size_t i = 0; i < detections.size(); ++i) {
    const auto& d = detections[i];
    if (!target.has_marker(d.id) || (i > 0 && detections[i - 1].id == d.id) ||
        (i + 1 < detections.size() && detections[i + 1].id == d.id))
      continue;
    if (d.id == target.pose_marker_id)
      pose_marker = &d;
    else
      others.push_back(&d);
  }
  std::vector<ScopeResult> scopes;
  if (pose_marker)
    scopes.push_back(
        solve_scope(pose_marker->id, {pose_marker}, detector.camera(), target, solvers));
  std::vector<const vision::Detection*> all;
  if (pose_marker) all.push_back(pose_marker);
  all.insert(all.end(), others.begin(), others.end());
  if (!all.empty())
    scopes.push_back(solve_scope("target", all, detector.camera(), target, solvers));

  if (!json) {
    print_text(path, detections, scopes);
    return true;
  }
  nlohmann::json out = {{"image", path},
                        {"detections", nlohmann::json::array()},
                        {"estimates", nlohmann::json::array()}};
  for (const auto& d : detections)
    out["detections"].push_back(detection_to_json(d));
  for (const auto& s : scopes) {
    if (!s.error.empty()) {
      out["estimates"].push_back({{"scope", s.scope}, {"error", s.error}});
      continue;
    }
    for (const auto& e : s.estimates) {
      nlohmann::json j = estimate_to_json(e);
      j["scope"] = s.scope;
      if (e.applicable() && !j.contains("ambiguity_ratio")) j["ambiguity_ratio"] = nullptr;
      out["estimates"].push_back(j);
    }
  }
  std::cout << out.dump() << std::endl;
  return true;
}

int run_detect(const Options& o) {
  std::optional<vision::Camera> camera;
  std::optional<vision::Target> target;
  try {
    camera = o.camera_file.empty() ? vision::Camera::paper_default()
                                   : vision::Camera::load(o.camera_file);
    target = o.target_file.empty() ? vision::Target::paper_default()
                                   : vision::Target::load(o.target_file);
  } catch (const vision::CalibrationError& e) {
    std::cerr << "rig detect: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const vision::TargetError& e) {
    std::cerr << "rig detect: " << e.what() << "\n";
    return kExitBadInput;
  }
  const vision::Codebook codebook;
  for (const auto& m : target->markers)
    if (m.id < 0 || static_cast<size_t>(m.id) >= codebook.size()) {
      std::cerr << "rig detect: target marker id " << m.id << " is not in the codebook (ids 0-"
                << codebook.size() - 1 << ")\n";
      return kExitBadInput;
    }
  const vision::Detector detector(*camera, codebook);
  const auto solvers = vision::make_all_solvers();
  bool all_ok = true;
  for (const auto& image : o.images)
    all_ok = detect_one(image, detector, *target, solvers, o.json) && all_ok;
  return all_ok ? kExitOk : kExitBadInput;
}

}  // namespace

void add_detect_command(CLI::App& app, ExitStatus& status) {
  auto* cmd = app.add_subcommand(
      "detect", "Detect and identify the fiducials in images and run every pose solver on them");
  auto o = std::make_shared<Options>();
  cmd->add_option("images", o->images,
                  "Image files (PNG, JPEG, TIFF, PGM, ...; 8/16-bit, grey or colour)")
      ->required();
  cmd->add_option("--camera", o->camera_file,
                  "Calibration file (OpenCV YAML/XML or ROS camera_info); default: the paper's "
                  "Sony XC-555, 736x571");
  cmd->add_option(
      "--target", o->target_file,
      "Target layout (TOML, see config/targets/paper.toml); default: the paper's sheet");
  cmd->add_flag("--json", o->json,
                "Print one JSON object per image, one per line: {\"image\", \"detections\", "
                "\"estimates\"}");
  cmd->footer(
      "Example: rig detect frame_0001.png frame_0002.png --camera cam.yaml "
      "--target config/targets/paper.toml --json\n"
      "Estimates are given with scope = the pose marker's id (its four corners) and scope =\n"
      "\"target\" (all detected markers of the layout, pose marker first).\n"
      "Exit codes: 0 ok, 2 bad input (an unreadable, empty, truncated or non-image file, an\n"
      "image whose size is not the camera's, a bad calibration or target file); the other\n"
      "images are still processed.");
  cmd->callback([&status, o] { status.code = run_detect(*o); });
}

}  // namespace rig
