// rig detect IMAGE...: the fiducials each detector (vision/detectors.hpp) finds
// in each image, and every pose solver's estimate from each detector's
// corners, on the pose marker alone and on the whole target. Ids outside the
// target layout are flagged; the detectors are those that decode the
// target's marker family (--detector to choose).
//
// --json prints one JSON object per image, one per line (a single image gives
// a single JSON document). Its shape is public:
//   {"image": PATH,
//    "detector": NAME, "detections": [...], "estimates": [...]   (the primary detector's)
//    "detectors": [{"detector": NAME, "detections": [...], "estimates": [...]}, ...]}
//   detections: [{"id", "rotation", "in_target", "corners": [[x, y] x 4], "quality":
//                    {"contrast", "bits_corrected", "edge_fit_residual_px"}}],
//   estimates: [{"solver", "scope", "R", "t", "distance_m",
//                   "reprojection_error_px", "converged", "ambiguity_ratio", ...}]
// The primary detector is the first of "detectors": rig's when it decodes the
// family and is chosen. "in_target" says whether the id is a marker of the
// layout (only those are solved on); quality fields a detector does not
// measure are 0.
// Corners are distorted pixels in OpenCV's convention (pixel centres at
// integer coordinates), in the order A, B, C, D of the target layout. "scope"
// is the pose marker's id (its four corners alone) or "target" (every
// detected marker of the layout, the pose marker's corners first). R and t
// are T_cam_target (metres); "ambiguity_ratio" is null where a solver does
// not define it. An image that cannot be used gives {"image", "error",
// "detections": [], "estimates": []}.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.hpp"
#include "estimate_json.hpp"
#include "vision/detector.hpp"
#include "vision/detector_image.hpp"
#include "vision/detectors.hpp"
#include "vision/frame_measurement.hpp"
#include "vision/marker_family.hpp"
#include "vision/target.hpp"

namespace rig::cli {
namespace {

struct Options {
  std::vector<std::string> images;
  std::string camera_file;
  std::string target_file;
  std::vector<std::string> detectors;
  bool json = false;
};

nlohmann::json detection_to_json(const vision::Detection& d, const vision::Target& target) {
  nlohmann::json corners = nlohmann::json::array();
  for (const auto& c : d.corners_px)
    corners.push_back({c.x(), c.y()});
  return {{"id", d.id},
          {"rotation", d.rotation},
          {"in_target", target.has_marker(d.id)},
          {"corners", corners},
          {"quality",
           {{"contrast", d.quality.contrast},
            {"bits_corrected", d.quality.bits_corrected},
            {"edge_fit_residual_px", d.quality.edge_fit_residual_px}}}};
}

// The scope as rig detect's JSON has always given it: the pose marker's id
// as a number, "target" as text.
nlohmann::json scope_json(const std::string& scope) {
  return scope == "target" ? nlohmann::json(scope) : nlohmann::json(std::stoi(scope));
}

void print_text(const std::string& image, const vision::DetectorMeasurement& m,
                const vision::Target& target) {
  std::printf("%s: %zu marker%s (detector %s)\n", image.c_str(), m.detections.size(),
              m.detections.size() == 1 ? "" : "s", m.detector.c_str());
  for (const auto& d : m.detections) {
    std::printf("  id %2d%s rot %d  corners", d.id,
                target.has_marker(d.id) ? "" : " (not in the target layout)", d.rotation);
    for (const auto& c : d.corners_px)
      std::printf(" (%.3f, %.3f)", c.x(), c.y());
    std::printf("  contrast %.0f  bits corrected %d  edge residual %.3f px\n", d.quality.contrast,
                d.quality.bits_corrected, d.quality.edge_fit_residual_px);
  }
  for (const auto& error : m.scope_errors)
    std::printf("  no estimate: %s: %s\n", error.scope.c_str(), error.message.c_str());
  std::string scope;
  for (const auto& s : m.estimates) {
    if (s.scope != scope) {
      scope = s.scope;
      std::printf("  %s:\n  %-20s %-9s %11s %10s %9s %9s\n",
                  scope == "target" ? "target" : ("marker " + scope).c_str(), "solver", "converged",
                  "distance_m", "reproj_px", "time_us", "ambiguity");
    }
    const vision::Estimate& e = s.estimate;
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

// Returns false when the image could not be used (the error is printed).
// `calibration` names the calibration in messages.
// One detector's detections and estimates as rig detect's JSON gives them.
nlohmann::json measurement_json(const vision::DetectorMeasurement& m,
                                const vision::Target& target) {
  nlohmann::json out = {{"detector", m.detector},
                        {"detections", nlohmann::json::array()},
                        {"estimates", nlohmann::json::array()}};
  for (const auto& d : m.detections)
    out["detections"].push_back(detection_to_json(d, target));
  for (const auto& error : m.scope_errors)
    out["estimates"].push_back({{"scope", scope_json(error.scope)}, {"error", error.message}});
  for (const auto& s : m.estimates) {
    nlohmann::json j = estimate_to_json(s.estimate);
    j["scope"] = scope_json(s.scope);
    if (s.estimate.applicable() && !j.contains("ambiguity_ratio")) j["ambiguity_ratio"] = nullptr;
    out["estimates"].push_back(j);
  }
  return out;
}

bool detect_one(const std::string& path, const vision::FrameMeasurer& measurer,
                const std::string& calibration, bool json) {
  vision::FrameMeasurement m;
  std::string error;
  try {
    const cv::Mat image = vision::read_image(path);
    if (const auto mismatch = measurer.camera().image_size_mismatch(
            image.size(), "image '" + path + "'", calibration))
      throw vision::ImageError(*mismatch + "; expected an image at the calibration's resolution");
    m = measurer.measure(image);
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
  const vision::Target& target = measurer.target();
  if (!json) {
    for (const vision::DetectorMeasurement& dm : m.detectors)
      print_text(path, dm, target);
    return true;
  }
  nlohmann::json out = measurement_json(m.primary(), target);
  out["image"] = path;
  out["detectors"] = nlohmann::json::array();
  for (const vision::DetectorMeasurement& dm : m.detectors)
    out["detectors"].push_back(measurement_json(dm, target));
  std::cout << out.dump() << std::endl;
  return true;
}

int run_detect(const Options& o) {
  const vision::Camera camera =
      o.camera_file.empty() ? vision::Camera::paper_default() : vision::Camera::load(o.camera_file);
  const vision::Target target =
      o.target_file.empty() ? vision::Target::paper_default() : vision::Target::load(o.target_file);
  const vision::MarkerFamily& family = vision::MarkerFamily::named(target.family);
  for (const auto& m : target.markers)
    if (!family.has_id(m.id))
      throw BadInput("target marker id " + std::to_string(m.id) + " is not in its family " +
                     family.name() + " (ids 0-" + std::to_string(family.size() - 1) + ")");
  std::vector<std::string> detectors = o.detectors;
  if (detectors.empty()) detectors = vision::detectors_for_family(target.family);
  for (const std::string& d : detectors)
    if (!vision::detector_reads(d, target.family)) {
      const bool known = std::find(vision::detector_names().begin(), vision::detector_names().end(),
                                   d) != vision::detector_names().end();
      std::string able;
      for (const std::string& a : vision::detectors_for_family(target.family))
        able += (able.empty() ? "" : ", ") + a;
      throw BadInput("--detector " + d + ": " +
                     (known ? "does not decode the target's family " + target.family
                            : "no such detector (" + vision::detector_names_text() + ")") +
                     "; expected one of the detectors that decode " + target.family + ": " +
                     (able.empty() ? std::string("none") : able));
    }
  const vision::FrameMeasurer measurer(camera, target, {}, detectors);
  const std::string calibration = o.camera_file.empty() ? "the built-in paper camera (no --camera)"
                                                        : "calibration '" + o.camera_file + "'";
  bool all_ok = true;
  for (const auto& image : o.images)
    all_ok = detect_one(image, measurer, calibration, o.json) && all_ok;
  return all_ok ? kExitOk : kExitBadInput;
}

}  // namespace

void add_detect_command(CLI::App& app, ExitStatus& status) {
  auto* cmd = app.add_subcommand(
      "detect", "Detect and identify the fiducials in images and run every pose solver on them");
  auto o = std::make_shared<Options>();
  cmd->add_option("images", o->images,
                  "Image files (PNG, JPEG, TIFF, PGM/PPM/PAM or BMP; 8/16-bit, grey or colour; "
                  "at most 268 Mpx and 1 GiB decoded)")
      ->required();
  cmd->add_option("--camera", o->camera_file,
                  "Calibration file (OpenCV YAML/XML or ROS camera_info); default: the paper's "
                  "Sony XC-555, 736x571");
  cmd->add_option(
      "--target", o->target_file,
      "Target layout (TOML, see config/targets/paper.toml); default: the paper's sheet");
  cmd->add_option("--detector", o->detectors,
                  "A detector to run (repeatable): rig, aruco:none, aruco:subpix, aruco:contour, "
                  "aruco:apriltag, apriltag:d1, apriltag:d2; default: every one that decodes the "
                  "target's marker family");
  cmd->add_flag("--json", o->json,
                "Print one JSON object per image, one per line: {\"image\", \"detections\", "
                "\"estimates\"}");
  cmd->footer(
      "Example: rig detect frame_0001.png frame_0002.png --camera cam.yaml "
      "--target config/targets/paper.toml --json\n"
      "Estimates are given with scope = the pose marker's id (its four corners) and scope =\n"
      "\"target\" (all detected markers of the layout, pose marker first).\n"
      "Exit codes: 0 ok, 2 bad input (an unreadable, empty, truncated, oversized or non-image\n"
      "file, an image whose size is not the camera's, a bad calibration or target file); the\n"
      "other images are still processed.");
  cmd->callback(
      [&status, o] { status.code = run_command("detect", [&] { return run_detect(*o); }); });
}

}  // namespace rig::cli
