#include "protocol.hpp"

#include <Eigen/Dense>
#include <cmath>

#include "config/json.hpp"

namespace rig::estimator::protocol {
namespace {

using nlohmann::json;

// A malformed answer: the failure names the field and what was expected.
struct Malformed {
  std::string reason;
};

[[noreturn]] void malformed(const std::string& field, const std::string& expected,
                            const json* value = nullptr) {
  throw Malformed{field + (value ? " = " + config::excerpt_json(*value) : ": missing") +
                  "; expected " + expected};
}

const json& member(const json& object, const std::string& key, const std::string& field) {
  const auto it = object.find(key);
  if (it == object.end()) malformed(field, "it to be present");
  return *it;
}

double finite_number(const json& v, const std::string& field) {
  if (!v.is_number()) malformed(field, "a number", &v);
  const double d = v.get<double>();
  if (!std::isfinite(d)) malformed(field, "a finite number", &v);
  return d;
}

// An array of exactly n finite numbers.
std::vector<double> numbers(const json& v, std::size_t n, const std::string& field) {
  if (!v.is_array() || v.size() != n)
    malformed(field, "an array of " + std::to_string(n) + " numbers", &v);
  std::vector<double> out;
  for (std::size_t i = 0; i < n; ++i)
    out.push_back(finite_number(v[i], field + "[" + std::to_string(i) + "]"));
  return out;
}

// R as 3 rows of 3: a rotation (orthonormal within 1e-6, det +1). The
// tolerance admits a rotation printed with 7 significant digits (rounding
// moves each entry by at most 5e-8, R^T R by about 3e-7) and refuses any
// matrix that is not one.
Eigen::Matrix3d rotation(const json& v, const std::string& field) {
  if (!v.is_array() || v.size() != 3) malformed(field, "3 rows of 3 numbers (row-major)", &v);
  Eigen::Matrix3d R;
  for (int i = 0; i < 3; ++i) {
    const auto row =
        numbers(v[static_cast<std::size_t>(i)], 3, field + "[" + std::to_string(i) + "]");
    for (int j = 0; j < 3; ++j)
      R(i, j) = row[static_cast<std::size_t>(j)];
  }
  const double off = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (off > 1e-6 || R.determinant() <= 0)
    malformed(field, "a rotation matrix (R^T R = I within 1e-6, det R = +1)", &v);
  return R;
}

std::array<Eigen::Vector2d, 4> four_pixels(const json& v, const std::string& field) {
  if (!v.is_array() || v.size() != 4) malformed(field, "4 corners [u, v] in pixels", &v);
  std::array<Eigen::Vector2d, 4> c;
  for (std::size_t k = 0; k < 4; ++k) {
    const auto p = numbers(v[k], 2, field + "[" + std::to_string(k) + "]");
    c[k] = {p[0], p[1]};
  }
  return c;
}

int marker_id(const json& v, const std::string& field) {
  if (!v.is_number_integer() || v.get<std::int64_t>() < 0 || v.get<std::int64_t>() > 1'000'000)
    malformed(field, "a marker id, an integer >= 0", &v);
  return v.get<int>();
}

ExternalPose read_pose(const json& p, const std::string& field) {
  if (!p.is_object()) malformed(field, "an object {\"scope\", \"R\", \"t_m\"}", &p);
  ExternalPose pose;
  if (const auto it = p.find("scope"); it != p.end()) {
    if (it->is_string() && *it == "target")
      pose.scope = "target";
    else if (it->is_number_integer())
      pose.scope = std::to_string(marker_id(*it, field + ".scope"));
    else
      malformed(field + ".scope", "\"target\" or a marker id", &*it);
  }
  pose.T_cam_target.R = rotation(member(p, "R", field + ".R"), field + ".R");
  const auto t = numbers(member(p, "t_m", field + ".t_m"), 3, field + ".t_m");
  pose.T_cam_target.t = {t[0], t[1], t[2]};
  if (const auto it = p.find("corners"); it != p.end()) {
    if (!it->is_array()) malformed(field + ".corners", "an array of {marker_id, corners_px}", &*it);
    for (std::size_t i = 0; i < it->size(); ++i) {
      const std::string f = field + ".corners[" + std::to_string(i) + "]";
      const json& c = (*it)[i];
      if (!c.is_object()) malformed(f, "an object {marker_id, corners_px}", &c);
      pose.corners_px.emplace_back(
          marker_id(member(c, "marker_id", f + ".marker_id"), f + ".marker_id"),
          four_pixels(member(c, "corners_px", f + ".corners_px"), f + ".corners_px"));
    }
  }
  return pose;
}

json parse_line(const std::string& line) {
  try {
    json j = config::parse_json(line, "the estimator's answer");
    if (!j.is_object()) malformed("the answer", "a JSON object on one line", &j);
    return j;
  } catch (const config::JsonInputError& e) {
    throw Malformed{e.what()};
  }
}

}  // namespace

std::string hello_line() {
  return json{{"type", "hello"}, {"protocol", kProtocolName}, {"version", kProtocolVersion}}
             .dump() +
         "\n";
}

std::optional<Failure> check_hello(const std::string& line, std::string& name,
                                   std::string& version) {
  try {
    const json j = parse_line(line);
    const json& type = member(j, "type", "type");
    if (type != "hello") malformed("type", "\"hello\" (the handshake comes first)", &type);
    const json& protocol = member(j, "protocol", "protocol");
    const json& v = member(j, "version", "version");
    if (protocol != kProtocolName || v != kProtocolVersion)
      return Failure{FailureKind::kProtocol,
                     "it speaks protocol " + config::excerpt_json(protocol) + " version " +
                         config::excerpt_json(v) + "; rig speaks \"" + kProtocolName +
                         "\" version " + std::to_string(kProtocolVersion)};
    const json& n = member(j, "name", "name");
    const json& ver = member(j, "estimator_version", "estimator_version");
    if (!n.is_string() || n.get<std::string>().empty()) malformed("name", "a non-empty string", &n);
    if (!ver.is_string()) malformed("estimator_version", "a string", &ver);
    name = n.get<std::string>();
    version = ver.get<std::string>();
    return std::nullopt;
  } catch (const Malformed& m) {
    return Failure{FailureKind::kMalformed, "handshake: " + m.reason};
  }
}

std::string frame_line(std::int64_t frame_id, const FrameRequest& request, int width_px,
                       int height_px, const std::string& camera, const std::string& target,
                       bool send_corners) {
  const json image = {{"path", request.image_path},
                      {"format", "png"},
                      {"width_px", width_px},
                      {"height_px", height_px}};
  std::string line = R"({"type":"frame","frame_id":)" + std::to_string(frame_id) + R"(,"image":)" +
                     image.dump() + R"(,"camera":)" + camera + R"(,"target":)" + target;
  if (send_corners && request.detections) {
    json detections = json::array();
    for (const vision::Detection& d : *request.detections) {
      json corners = json::array();
      for (const auto& c : d.corners_px)
        corners.push_back({c.x(), c.y()});
      detections.push_back({{"marker_id", d.id}, {"corners_px", std::move(corners)}});
    }
    line += R"(,"detections":)" + detections.dump();
  }
  return line + "}\n";
}

void read_result(const std::string& line, std::int64_t frame_id, FrameResult& result) {
  try {
    const json j = parse_line(line);
    const json& type = member(j, "type", "type");
    const json& id = member(j, "frame_id", "frame_id");
    if (id != frame_id) malformed("frame_id", "the frame's id " + std::to_string(frame_id), &id);
    if (type == "error") {
      const json& message = member(j, "message", "message");
      if (!message.is_string()) malformed("message", "a string", &message);
      result.failure =
          Failure{FailureKind::kDeclined, config::excerpt(message.get<std::string>(), 200)};
      return;
    }
    if (type != "result") malformed("type", "\"result\" or \"error\"", &type);
    const json& poses = member(j, "poses", "poses");
    if (!poses.is_array()) malformed("poses", "an array of poses (may be empty)", &poses);
    for (std::size_t i = 0; i < poses.size(); ++i)
      result.poses.push_back(read_pose(poses[i], "poses[" + std::to_string(i) + "]"));
    if (const auto it = j.find("time_us"); it != j.end()) {
      const double us = finite_number(*it, "time_us");
      if (us < 0) malformed("time_us", "a time >= 0 in microseconds", &*it);
      result.estimator_time_us = us;
    }
  } catch (const Malformed& m) {
    result.poses.clear();
    result.estimator_time_us.reset();
    result.failure = Failure{FailureKind::kMalformed, m.reason};
  }
}

}  // namespace rig::estimator::protocol
