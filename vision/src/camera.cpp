#include "vision/camera.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/core/persistence.hpp>
#include <sstream>
#include <tuple>

#include "calibration_yaml.hpp"
#include "lens_model.hpp"

namespace vision {
namespace {

bool finite_all(std::initializer_list<double> values) {
  for (double v : values)
    if (!std::isfinite(v)) return false;
  return true;
}

[[noreturn]] void fail(const std::string& path, const std::string& key, const std::string& what) {
  throw CalibrationError("calibration file '" + path + "': key '" + key + "' " + what);
}

using calibration::Node;

bool is_number(const Node& n) {
  return n.kind == Node::Kind::kScalar && n.number.has_value();
}

int read_int(const Node& root, const std::string& path, const std::string& key) {
  const Node* n = root.find(key);
  if (!n) fail(path, key, "is missing (expected a positive integer)");
  if (!is_number(*n) || !n->integer) fail(path, key, "must be a positive integer");
  const double v = *n->number;
  if (v <= 0 || v > std::numeric_limits<int>::max())
    fail(path, key, "must be a positive integer, got " + n->text);
  return static_cast<int>(v);
}

// A calibration matrix is at most 3x3 (or 1x14 coefficients): rows and cols
// are bounded before the values are read (a file declaring 10^5 x 10^5 made
// OpenCV allocate 80 GB; found by fuzzing).
constexpr int kMaxMatrixSide = 16;
std::pair<int, int> matrix_shape(const Node& n, const std::string& path, const std::string& key) {
  const Node* r = n.find("rows");
  const Node* c = n.find("cols");
  if (!r || !c || !is_number(*r) || !is_number(*c) || !r->integer || !c->integer)
    fail(path, key, "must give integer rows and cols");
  const double rows = *r->number, cols = *c->number;
  if (rows < 1 || cols < 1 || rows > kMaxMatrixSide || cols > kMaxMatrixSide)
    fail(path, key,
         "declares rows x cols = " + r->text + "x" + c->text + "; expected 1 to " +
             std::to_string(kMaxMatrixSide) + " of each");
  return {static_cast<int>(rows), static_cast<int>(cols)};
}

// The numbers of a sequence; `what` names it in errors.
std::vector<double> numbers(const Node& seq, const std::string& path, const std::string& key,
                            const std::string& what) {
  if (seq.kind != Node::Kind::kSequence) fail(path, key, what + " must be a sequence of numbers");
  std::vector<double> values;
  for (const Node& item : seq.items) {
    if (!is_number(item)) fail(path, key, what + " holds a value that is not a number");
    values.push_back(*item.number);
  }
  return values;
}

// Reads a numeric matrix stored either as an OpenCV matrix (`!!opencv-matrix`
// or XML `type_id="opencv-matrix"`: rows, cols, dt, data) or as a ROS map
// {rows, cols, data}, or as a plain sequence (one row). Returns the values
// row-major and the shape.
std::vector<double> read_matrix(const Node& root, const std::string& path, const std::string& key,
                                int* rows, int* cols) {
  const Node* n = root.find(key);
  if (!n) fail(path, key, "is missing");
  std::vector<double> values;
  if (n->kind == Node::Kind::kMap && (n->find("dt") || n->tag == "opencv-matrix")) {
    std::tie(*rows, *cols) = matrix_shape(*n, path, key);
    const Node* dt = n->find("dt");
    // One channel of OpenCV's element types: d double, f float, i s w u c integers.
    if (!dt || dt->kind != Node::Kind::kScalar || dt->text.size() != 1 ||
        std::string("dfiswuc").find(dt->text) == std::string::npos)
      fail(path, key,
           "must give dt, one of d, f, i, s, w, u, c (a one-channel OpenCV matrix)" +
               (dt && dt->kind == Node::Kind::kScalar ? ", got '" + dt->text + "'" : ""));
    const Node* data = n->find("data");
    if (!data) fail(path, key, "has no data");
    values = numbers(*data, path, key, "data");
    if (dt->text == "f")
      for (double& v : values)
        v = static_cast<float>(v);  // what OpenCV stores for dt f
  } else if (n->kind == Node::Kind::kMap && n->find("data")) {
    std::tie(*rows, *cols) = matrix_shape(*n, path, key);
    values = numbers(*n->find("data"), path, key, "data");
  } else if (n->kind == Node::Kind::kSequence) {
    values = numbers(*n, path, key, "it");
    *rows = 1;
    *cols = static_cast<int>(values.size());
  } else {
    fail(path, key, "is not a matrix (expected an OpenCV matrix or {rows, cols, data})");
  }
  if (static_cast<long>(values.size()) != static_cast<long>(*rows) * *cols)
    fail(path, key,
         "has " + std::to_string(values.size()) +
             " values but rows x cols = " + std::to_string(*rows) + "x" + std::to_string(*cols));
  for (double v : values)
    if (!std::isfinite(v)) fail(path, key, "holds a value that is not finite");
  return values;
}

// An XML calibration as OpenCV's XML reader parsed it (its bounds were
// checked first: check_text_bytes, check_xml_nesting), as the same nodes as
// a YAML one.
Node from_file_node(const cv::FileNode& n) {
  Node out;
  if (n.isMap()) {
    out.kind = Node::Kind::kMap;
    for (const std::string& key : n.keys())
      out.entries.emplace_back(key, from_file_node(n[key]));
  } else if (n.isSeq()) {
    out.kind = Node::Kind::kSequence;
    for (const cv::FileNode& item : n)
      out.items.push_back(from_file_node(item));
  } else if (n.isInt()) {
    out.number = static_cast<int>(n);
    out.integer = true;
    out.text = std::to_string(static_cast<int>(n));
  } else if (n.isReal()) {
    out.number = static_cast<double>(n);
    out.text = std::to_string(*out.number);
  } else if (n.isString()) {
    out.text = static_cast<std::string>(n);
  }
  return out;
}

// The bounds of a calibration file: OpenCV's XML parser recurses once per
// element level and would exhaust the stack on a file nested thousands of
// levels deep; a calibration nests 3 levels and is a few KiB. (The YAML
// reader bounds its own nesting: calibration::kMaxBlockDepth.)
constexpr std::size_t kMaxCalibrationBytes = 1u << 20;
constexpr int kMaxCalibrationDepth = 32;

[[noreturn]] void too_deep(const std::string& path, int line, const std::string& what) {
  throw CalibrationError("calibration file '" + path + "': line " + std::to_string(line) + ": " +
                         what + "; expected a calibration nesting at most " +
                         std::to_string(kMaxCalibrationDepth) + " levels deep");
}

// A YAML/XML calibration is text: OpenCV 4.6's XML reader dereferences a
// null pointer on a NUL byte inside a tag (found by fuzzing), so control
// bytes other than tab, carriage return and line feed are refused first.
void check_text_bytes(const std::string& path, const std::string& text) {
  int line = 1;
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '\n') ++line;
    if ((c < 0x20 && c != '\t' && c != '\r' && c != '\n') || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02x", c);
      throw CalibrationError("calibration file '" + path + "': line " + std::to_string(line) +
                             ": holds the control byte " + hex + "; expected a YAML/XML text file");
    }
  }
}

// XML: elements nest by start tags; <?...?>, <!...> and empty-element tags
// do not open a level. Every tag must be closed by '>': OpenCV 4.6's XML
// reader reads past the end of its buffer on a tag that the file ends inside
// of (a last byte '=' of an attribute, found by fuzzing).
void check_xml_nesting(const std::string& path, const std::string& text) {
  int depth = 0, line = 1;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\n') ++line;
    if (text[i] != '<') continue;
    if (text.find('>', i) == std::string::npos)
      throw CalibrationError("calibration file '" + path + "': line " + std::to_string(line) +
                             ": the file ends inside a tag; expected '>' to close it");
    const char next = text[i + 1];
    if (next == '/') {
      if (depth > 0) --depth;
    } else if (next != '?' && next != '!') {
      const auto close = text.find('>', i);
      const bool empty_element = close != std::string::npos && close > 0 && text[close - 1] == '/';
      if (!empty_element && ++depth > kMaxCalibrationDepth)
        too_deep(
            path, line,
            "elements nested more than " + std::to_string(kMaxCalibrationDepth) + " levels deep");
    }
  }
}

Node read_xml(const std::string& path, const std::string& text) {
  check_xml_nesting(path, text);
  if (text.compare(0, 5, "<?xml") != 0)
    throw CalibrationError("calibration file '" + path +
                           "': starts with '<' but not with an XML declaration; expected <?xml "
                           "version=\"1.0\"?> (OpenCV XML) or YAML");
  cv::FileStorage fs;
  try {
    fs.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_XML);
  } catch (const cv::Exception& e) {
    throw CalibrationError("calibration file '" + path + "': not an XML calibration: " + e.what());
  } catch (const std::exception& e) {
    // OpenCV 4.6's parsers also throw what is not a cv::Exception: a
    // std::length_error ("basic_string::_M_create") on some malformed files
    // (found by libFuzzer), which a catch of cv::Exception alone let
    // terminate the process.
    throw CalibrationError("calibration file '" + path +
                           "': not an XML calibration: OpenCV's XML reader failed (" + e.what() +
                           ")");
  }
  if (!fs.isOpened())
    throw CalibrationError("calibration file '" + path + "': not an XML calibration");
  return from_file_node(fs.root());
}

// The distortion coefficients in OpenCV's order (camera.hpp): 4, 5, 8, 12
// or 14 values, the rational k4..k6 and the sensor tilt tau zero.
Distortion distortion_of(const std::string& path, const std::vector<double>& d, int rows,
                         int cols) {
  const std::string key = "distortion_coefficients";
  const std::size_t n = d.size();
  if ((rows != 1 && cols != 1) || (n != 4 && n != 5 && n != 8 && n != 12 && n != 14))
    fail(path, key,
         "must be a vector of 4, 5, 8, 12 or 14 values (OpenCV's order k1 k2 p1 p2 k3 k4 k5 k6 "
         "s1 s2 s3 s4 tau_x tau_y), got " +
             std::to_string(n) + " as " + std::to_string(rows) + "x" + std::to_string(cols));
  for (std::size_t i = 5; i < std::min<std::size_t>(n, 8); ++i)
    if (d[i] != 0)
      fail(path, key,
           "has a non-zero rational term k" + std::to_string(i - 1) +
               " (OpenCV's rational model), which this camera model does not represent; "
               "expected k4 = k5 = k6 = 0 (Brown-Conrady with thin prism)");
  for (std::size_t i = 12; i < n; ++i)
    if (d[i] != 0)
      fail(path, key,
           "has a non-zero sensor tilt tau (coefficients 13-14), which this camera model does "
           "not represent; expected 0");
  Distortion out{d[0], d[1], d[2], d[3], n > 4 ? d[4] : 0.0};
  if (n >= 12) {
    out.s1 = d[8];
    out.s2 = d[9];
    out.s3 = d[10];
    out.s4 = d[11];
  }
  return out;
}

}  // namespace

Camera::Camera(const Intrinsics& intrinsics, const Distortion& distortion, int width_px,
               int height_px)
    : intrinsics_(intrinsics), distortion_(distortion), width_px_(width_px), height_px_(height_px) {
  if (!finite_all({intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy}) ||
      intrinsics.fx <= 0 || intrinsics.fy <= 0)
    throw std::invalid_argument(
        "camera intrinsics: fx and fy must be finite and > 0, cx and cy finite");
  if (!finite_all({distortion.k1, distortion.k2, distortion.p1, distortion.p2, distortion.k3,
                   distortion.s1, distortion.s2, distortion.s3, distortion.s4}))
    throw std::invalid_argument("camera distortion: every coefficient must be finite");
  if (width_px <= 0 || height_px <= 0)
    throw std::invalid_argument("camera image size: width and height must be > 0, got " +
                                std::to_string(width_px) + "x" + std::to_string(height_px));
}

Camera Camera::paper_default() {
  return Camera({706.1, 731.1, 388.0, 269.6}, {-0.2279, 0.1479, -0.0007985, 0.0006245, 0.0}, 736,
                571);
}

Camera Camera::load(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
    throw CalibrationError("calibration file '" + path +
                           "': is not a regular file; expected a YAML/XML calibration file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw CalibrationError("calibration file '" + path + "': cannot be opened");
  std::string text(kMaxCalibrationBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxCalibrationBytes)
    throw CalibrationError("calibration file '" + path + "': is larger than " +
                           std::to_string(kMaxCalibrationBytes >> 20) +
                           " MiB; expected a YAML/XML calibration of a few KiB");
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw CalibrationError("calibration file '" + path + "': is empty");
  check_text_bytes(path, text);

  // YAML is read by rig's own reader of the subset calibrations use
  // (calibration_yaml.hpp): OpenCV 4.6's YAML reader can abort the process on
  // malformed input. XML goes to OpenCV's XML reader after the bounds above.
  // The format is what the file holds, whatever its name: XML starts with '<'
  // (OpenCV picks its parser by the first bytes too; from "<?xml" on, only
  // its XML parser sees the file).
  const std::size_t start = text.find_first_not_of(" \t\r\n");
  const Node root =
      text[start] == '<' ? read_xml(path, text.substr(start)) : calibration::parse_yaml(path, text);
  // A file whose top level is a list or a scalar is refused here.
  if (root.kind != Node::Kind::kMap)
    throw CalibrationError("calibration file '" + path +
                           "': the top level is not a map of keys; expected image_width, "
                           "image_height, camera_matrix and distortion_coefficients");

  const int width = read_int(root, path, "image_width");
  const int height = read_int(root, path, "image_height");

  int rows = 0, cols = 0;
  const auto k = read_matrix(root, path, "camera_matrix", &rows, &cols);
  if (rows != 3 || cols != 3)
    fail(path, "camera_matrix",
         "must be 3x3, got " + std::to_string(rows) + "x" + std::to_string(cols));
  if (k[1] != 0 || k[3] != 0 || k[6] != 0 || k[7] != 0 || k[8] != 1)
    fail(path, "camera_matrix", "must have the form [fx 0 cx; 0 fy cy; 0 0 1] (no skew)");
  if (k[0] <= 0 || k[4] <= 0) fail(path, "camera_matrix", "must have fx > 0 and fy > 0");

  const Node* model = root.find("distortion_model");
  if (model && model->kind != Node::Kind::kScalar)
    fail(path, "distortion_model", "must be a name (expected plumb_bob or rational_polynomial)");
  if (model && model->text != "plumb_bob" && model->text != "rational_polynomial")
    fail(path, "distortion_model",
         "'" + model->text + "' is not supported (expected plumb_bob or rational_polynomial)");
  const auto d = read_matrix(root, path, "distortion_coefficients", &rows, &cols);
  return Camera({k[0], k[4], k[2], k[5]}, distortion_of(path, d, rows, cols), width, height);
}

void Camera::save(const std::string& path) const {
  cv::FileStorage fs(path, cv::FileStorage::WRITE);
  if (!fs.isOpened()) throw CalibrationError("calibration file '" + path + "': cannot be written");
  fs << "image_width" << width_px_ << "image_height" << height_px_;
  fs << "camera_matrix" << camera_matrix_cv() << "distortion_coefficients" << distortion_cv();
}

bool Camera::has_distortion() const {
  const auto& d = distortion_;
  return d.k1 != 0 || d.k2 != 0 || d.p1 != 0 || d.p2 != 0 || d.k3 != 0 || d.has_thin_prism();
}

std::optional<std::string> Camera::image_size_mismatch(const cv::Size& image_size,
                                                       const std::string& image,
                                                       const std::string& calibration) const {
  if (image_size.width == width_px_ && image_size.height == height_px_) return std::nullopt;
  const auto size_text = [](int width, int height) {
    return std::to_string(width) + "x" + std::to_string(height) + " px";
  };
  return calibration + " is for " + size_text(width_px_, height_px_) + " but " + image + " is " +
         size_text(image_size.width, image_size.height);
}

Eigen::Matrix3d Camera::K() const {
  Eigen::Matrix3d k;
  k << intrinsics_.fx, 0, intrinsics_.cx, 0, intrinsics_.fy, intrinsics_.cy, 0, 0, 1;
  return k;
}

cv::Mat Camera::camera_matrix_cv() const {
  return (cv::Mat_<double>(3, 3) << intrinsics_.fx, 0, intrinsics_.cx, 0, intrinsics_.fy,
          intrinsics_.cy, 0, 0, 1);
}

cv::Mat Camera::distortion_cv() const {
  const auto& d = distortion_;
  if (!d.has_thin_prism()) return (cv::Mat_<double>(1, 5) << d.k1, d.k2, d.p1, d.p2, d.k3);
  return (cv::Mat_<double>(1, 12) << d.k1, d.k2, d.p1, d.p2, d.k3, 0, 0, 0, d.s1, d.s2, d.s3, d.s4);
}

Eigen::Vector2d Camera::project(const Eigen::Vector3d& p_cam) const {
  return distort_normalized(p_cam.head<2>() / p_cam.z());
}

Eigen::Vector2d Camera::distort_normalized(const Eigen::Vector2d& xy) const {
  return detail::distort_normalized(intrinsics_, distortion_, xy);
}

Eigen::Matrix2d Camera::distort_jacobian(const Eigen::Vector2d& xy) const {
  return detail::distort_jacobian(intrinsics_, distortion_, xy);
}

bool Camera::undistort_point(const Eigen::Vector2d& pixel, Eigen::Vector2d* xy) const {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  *xy = Eigen::Vector2d(nan, nan);
  if (!pixel.allFinite()) return false;
  // Start from the distorted normalized point: for real lenses the correction
  // is small and Newton converges quadratically from there in 3-6 steps. It
  // runs on to the rounding floor (1e-12 px) so that the answer is the inverse
  // to the last digits, and is accepted within kUndistortTolerancePx.
  constexpr double kRoundingFloorPx = 1e-12;
  Eigen::Vector2d x((pixel.x() - intrinsics_.cx) / intrinsics_.fx,
                    (pixel.y() - intrinsics_.cy) / intrinsics_.fy);
  Eigen::Vector2d best = x;
  double best_residual = std::numeric_limits<double>::infinity();
  constexpr int kMaxIterations = 50;
  for (int i = 0; i < kMaxIterations; ++i) {
    const Eigen::Vector2d residual = distort_normalized(x) - pixel;  // pixels
    if (!residual.allFinite()) break;
    if (residual.norm() < best_residual) {
      best_residual = residual.norm();
      best = x;
    }
    if (best_residual <= kRoundingFloorPx) break;
    const Eigen::Matrix2d j = distort_jacobian(x);
    // A vanishing Jacobian determinant marks the fold of the polynomial model,
    // beyond which it is not invertible.
    if (!(std::abs(j.determinant()) > 1e-12 * intrinsics_.fx * intrinsics_.fy)) break;
    x -= j.inverse() * residual;
  }
  if (!(best_residual <= kUndistortTolerancePx)) return false;
  // A root past the fold (where the radial model turns back) is not where any
  // ray lands: only the branch that contains the centre is the lens. On it,
  // r_d(r) = r (1 + k1 r^2 + k2 r^4 + k3 r^6) increases from 0 to r: its
  // derivative 1 + 3 k1 r^2 + 5 k2 r^4 + 7 k3 r^6 stays positive (checked at
  // 32 radii; a fold narrower than r/32 would need coefficients no lens has).
  const auto& d = distortion_;
  const double r2_max = best.squaredNorm();
  for (int k = 1; k <= 32; ++k) {
    const double r2 = r2_max * (k / 32.0) * (k / 32.0);
    if (!(1 + r2 * (3 * d.k1 + r2 * (5 * d.k2 + r2 * 7 * d.k3)) > 0)) return false;
  }
  *xy = best;
  return true;
}

std::vector<Eigen::Vector2d> Camera::undistort_points(
    const std::vector<Eigen::Vector2d>& pixels) const {
  std::vector<Eigen::Vector2d> out(pixels.size());
  for (size_t i = 0; i < pixels.size(); ++i)
    undistort_point(pixels[i], &out[i]);
  return out;
}

}  // namespace vision
