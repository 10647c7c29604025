// rig solve FILE|-: every pose solver on one JSON problem, side by side.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "estimate_json.hpp"
#include "vision/solvers.hpp"

namespace rig::cli {
namespace {

// Bad input to `rig solve`; the message names the key and what was expected
// (run_solve adds the problem's name).
struct ProblemError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Problem {
  std::optional<vision::Camera> camera;
  std::vector<Eigen::Vector3d> object_points;
  std::vector<Eigen::Vector2d> image_points_px;
};

double finite_number(const nlohmann::json& j, const std::string& where) {
  if (!j.is_number()) throw ProblemError(where + " must be a number, got " + j.dump());
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw ProblemError(where + " must be finite, got " + j.dump());
  return v;
}

template <int N>
std::vector<Eigen::Matrix<double, N, 1>> read_points(const nlohmann::json& root,
                                                     const std::string& key) {
  if (!root.contains(key)) throw ProblemError("key '" + key + "' is missing");
  const auto& arr = root[key];
  if (!arr.is_array())
    throw ProblemError("'" + key + "' must be an array of [" + (N == 3 ? "x, y, z" : "u, v") + "]");
  std::vector<Eigen::Matrix<double, N, 1>> out;
  for (size_t i = 0; i < arr.size(); ++i) {
    const std::string where = key + "[" + std::to_string(i) + "]";
    if (!arr[i].is_array() || arr[i].size() != N)
      throw ProblemError(where + " must be an array of " + std::to_string(N) + " numbers, got " +
                         arr[i].dump());
    Eigen::Matrix<double, N, 1> p;
    for (int k = 0; k < N; ++k)
      p(k) = finite_number(arr[i][k], where + "[" + std::to_string(k) + "]");
    out.push_back(p);
  }
  return out;
}

vision::Camera read_camera(const nlohmann::json& j) {
  if (!j.is_object())
    throw ProblemError("'camera' must be an object {fx, fy, cx, cy, dist, width, height}");
  auto need = [&](const char* k) -> const nlohmann::json& {
    if (!j.contains(k)) throw ProblemError(std::string("key 'camera.") + k + "' is missing");
    return j[k];
  };
  const vision::Intrinsics in{
      finite_number(need("fx"), "camera.fx"), finite_number(need("fy"), "camera.fy"),
      finite_number(need("cx"), "camera.cx"), finite_number(need("cy"), "camera.cy")};
  vision::Distortion d;
  if (j.contains("dist")) {
    const auto& dist = j["dist"];
    if (!dist.is_array() || dist.size() < 4 || dist.size() > 5)
      throw ProblemError("'camera.dist' must be [k1, k2, p1, p2] or [k1, k2, p1, p2, k3], got " +
                         dist.dump());
    double* fields[] = {&d.k1, &d.k2, &d.p1, &d.p2, &d.k3};
    for (size_t k = 0; k < dist.size(); ++k)
      *fields[k] = finite_number(dist[k], "camera.dist[" + std::to_string(k) + "]");
  }
  const auto size = [&](const char* k) {
    const auto& v = need(k);
    if (!v.is_number_integer() || v.get<long long>() <= 0)
      throw ProblemError(std::string("'camera.") + k + "' must be a positive integer, got " +
                         v.dump());
    return static_cast<int>(v.get<long long>());
  };
  try {
    return vision::Camera(in, d, size("width"), size("height"));
  } catch (const std::invalid_argument& e) {
    throw ProblemError(e.what());
  }
}

Problem read_problem(const std::string& source) {
  std::string text;
  std::filesystem::path base = ".";
  if (source == "-") {
    text.assign(std::istreambuf_iterator<char>(std::cin), {});
  } else {
    std::ifstream in(source);
    if (!in) throw ProblemError("cannot be opened");
    text.assign(std::istreambuf_iterator<char>(in), {});
    base = std::filesystem::path(source).parent_path();
  }
  nlohmann::json root;
  try {
    root = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw ProblemError(std::string("is not valid JSON: ") + e.what());
  }
  if (!root.is_object()) throw ProblemError("must be a JSON object");
  Problem p;
  if (root.contains("camera") && root.contains("camera_file"))
    throw ProblemError("give either 'camera' or 'camera_file', not both");
  if (root.contains("camera")) {
    p.camera = read_camera(root["camera"]);
  } else if (root.contains("camera_file")) {
    if (!root["camera_file"].is_string()) throw ProblemError("'camera_file' must be a path string");
    std::filesystem::path path = root["camera_file"].get<std::string>();
    if (path.is_relative()) path = base / path;  // relative to the problem file
    try {
      p.camera = vision::Camera::load(path.string());
    } catch (const vision::CalibrationError& e) {
      throw ProblemError(e.what());
    }
  } else {
    throw ProblemError("key 'camera' (or 'camera_file') is missing");
  }
  p.object_points = read_points<3>(root, "object_points");
  p.image_points_px = read_points<2>(root, "image_points");
  return p;
}

void print_table(const std::vector<vision::Estimate>& estimates) {
  std::printf("%-20s %-9s %11s %10s %6s %9s %9s  %s\n", "solver", "converged", "distance_m",
              "reproj_px", "iters", "time_us", "ambiguity", "t_cam_target (m)");
  for (const auto& e : estimates) {
    if (!e.applicable()) {
      std::printf("%-20s skipped: %s\n", e.solver.c_str(), e.message.c_str());
      continue;
    }
    const std::string ambiguity =
        e.ambiguity_ratio ? std::to_string(*e.ambiguity_ratio).substr(0, 6) : "-";
    std::printf("%-20s %-9s %11.6f %10.4f %6d %9.1f %9s  (%.5f, %.5f, %.5f)%s%s\n",
                e.solver.c_str(), e.converged ? "yes" : "no", e.distance_m, e.reprojection_error_px,
                e.iterations, e.time_us, ambiguity.c_str(), e.T_cam_target.t.x(),
                e.T_cam_target.t.y(), e.T_cam_target.t.z(), e.converged ? "" : "  ",
                e.converged ? "" : vision::to_string(e.termination));
  }
}

int run_solve(const std::string& source, bool json) {
  const std::string name = source == "-" ? "standard input" : "'" + source + "'";
  Problem problem;
  vision::Correspondences c;
  read_input("problem " + name, [&] {
    problem = read_problem(source);
    c = vision::make_correspondences(*problem.camera, problem.object_points,
                                     problem.image_points_px);
  });
  std::vector<vision::Estimate> estimates;
  bool any_converged = false, any_behind = false;
  for (const auto& solver : vision::make_all_solvers()) {
    estimates.push_back(solver->solve(c));
    any_converged = any_converged || estimates.back().converged;
    any_behind = any_behind || estimates.back().termination == vision::Termination::kBehindCamera;
  }
  if (json) {
    nlohmann::json out = {{"estimates", nlohmann::json::array()}};
    for (const auto& e : estimates)
      out["estimates"].push_back(estimate_to_json(e));
    std::cout << out.dump(2) << "\n";
  } else {
    print_table(estimates);
  }
  if (!any_converged) {
    std::cerr << "rig solve: problem " << name << ": no solver found a pose"
              << (any_behind ? " that puts every object point in front of the camera" : "")
              << " (expected image points of the object points as seen by this camera)\n";
    return kExitBadInput;
  }
  return kExitOk;
}

}  // namespace

void add_solve_command(CLI::App& app, ExitStatus& status) {
  auto* cmd = app.add_subcommand("solve", "Run every pose solver on one 2D-3D problem (JSON)");
  auto source = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("problem", *source,
                  "JSON problem file, or - for standard input: {\"camera\": {fx, fy, cx, cy, "
                  "dist: [k1,k2,p1,p2,k3], width, height}} or {\"camera_file\": PATH}, "
                  "\"object_points\": [[x,y,z],...] (metres, target frame), \"image_points\": "
                  "[[u,v],...] (pixels, distorted)")
      ->required();
  cmd->add_flag("--json", *json, "Print {\"estimates\": [...]} as JSON instead of a table");
  cmd->footer(
      "Example: rig solve config/problems/paper_marker.json --json\n"
      "Exit codes: 0 ok, 2 bad input (malformed JSON, fewer than 4 points, counts that differ,\n"
      "non-finite values, degenerate points, or no pose in front of the camera).");
  cmd->callback([&status, source, json] {
    status.code = run_command("solve", [&] { return run_solve(*source, *json); });
  });
}

}  // namespace rig::cli
