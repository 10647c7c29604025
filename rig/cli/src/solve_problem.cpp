#include "solve_problem.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "config/json.hpp"

namespace rig::cli {
namespace {

double finite_number(const nlohmann::json& j, const std::string& where) {
  if (!j.is_number())
    throw ProblemError(where + " must be a number, got " + config::excerpt_json(j));
  const double v = j.get<double>();
  if (!std::isfinite(v))
    throw ProblemError(where + " must be finite, got " + config::excerpt_json(j));
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
                         config::excerpt_json(arr[i]));
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
    if (!dist.is_array() || (dist.size() != 4 && dist.size() != 5 && dist.size() != 12))
      throw ProblemError(
          "'camera.dist' must be [k1, k2, p1, p2], [k1, k2, p1, p2, k3] or OpenCV's 12 "
          "[k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4] with k4 = k5 = k6 = 0, got " +
          config::excerpt_json(dist));
    double rational = 0;  // k4..k6: OpenCV's rational model, which vision::Camera does not hold
    double* fields[] = {&d.k1,     &d.k2,     &d.p1, &d.p2, &d.k3, &rational,
                        &rational, &rational, &d.s1, &d.s2, &d.s3, &d.s4};
    for (size_t k = 0; k < dist.size(); ++k) {
      *fields[k] = finite_number(dist[k], "camera.dist[" + std::to_string(k) + "]");
      if (rational != 0)
        throw ProblemError("'camera.dist[" + std::to_string(k) +
                           "]' is a rational term k4..k6 of OpenCV's rational model, which is "
                           "not supported; expected 0, got " +
                           config::excerpt_json(dist[k]));
    }
  }
  const auto size = [&](const char* k) {
    const auto& v = need(k);
    if (!v.is_number_integer() || v.get<long long>() <= 0)
      throw ProblemError(std::string("'camera.") + k + "' must be a positive integer, got " +
                         config::excerpt_json(v));
    return static_cast<int>(v.get<long long>());
  };
  try {
    return vision::Camera(in, d, size("width"), size("height"));
  } catch (const std::invalid_argument& e) {
    throw ProblemError(e.what());
  }
}

}  // namespace

Problem parse_problem(const std::string& text, const std::filesystem::path& base) {
  const config::JsonLimits limits;
  nlohmann::json root;
  try {
    root = config::parse_json(text, "", limits);
  } catch (const config::JsonInputError& e) {
    // parse_json's message starts with the (empty) input name and ": ".
    throw ProblemError(std::string(e.what()).substr(2));
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

}  // namespace rig::cli
