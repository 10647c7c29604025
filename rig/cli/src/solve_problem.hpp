// The problem `rig solve` reads: a camera and 2D-3D correspondences as JSON
// (the --help of `rig solve` gives the shape).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "vision/camera.hpp"

namespace rig::cli {

// Bad input to `rig solve`; the message names the key and what was expected
// (run_solve adds the problem's name).
struct ProblemError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Problem {
  std::optional<vision::Camera> camera;
  std::vector<Eigen::Vector3d> object_points;    // metres, target frame
  std::vector<Eigen::Vector2d> image_points_px;  // pixels, distorted
};

// Parses a problem's JSON text (bounded: config::parse_json); a relative
// "camera_file" is relative to `base`. Throws ProblemError naming the key,
// with at most an excerpt of the offending value; vision::Camera::load's
// errors become ProblemError too.
Problem parse_problem(const std::string& text, const std::filesystem::path& base);

}  // namespace rig::cli
