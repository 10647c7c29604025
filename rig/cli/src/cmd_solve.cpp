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
#include "config/json.hpp"
#include "estimate_json.hpp"
#include "solve_problem.hpp"
#include "vision/solvers.hpp"

namespace rig::cli {
namespace {

// The first `max_bytes` bytes of `in` (all of it when shorter).
std::string read_at_most(std::istream& in, std::size_t max_bytes) {
  std::string text(max_bytes, '\0');
  in.read(text.data(), static_cast<std::streamsize>(max_bytes));
  text.resize(static_cast<std::size_t>(in.gcount()));
  return text;
}

Problem read_problem(const std::string& source) {
  std::string text;
  std::filesystem::path base = ".";
  const config::JsonLimits limits;
  if (source == "-") {
    text = read_at_most(std::cin, limits.max_bytes + 1);
  } else {
    std::error_code ec;
    if (std::filesystem::is_directory(source, ec))
      throw ProblemError("is a directory; expected a JSON problem file");
    std::ifstream in(source);
    if (!in) throw ProblemError("cannot be opened");
    text = read_at_most(in, limits.max_bytes + 1);
    base = std::filesystem::path(source).parent_path();
  }
  return parse_problem(text, base);
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
                  "dist: [k1,k2,p1,p2,k3] or OpenCV's 12 with s1..s4, width, height}} or "
                  "{\"camera_file\": PATH}, "
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
