#include "vision/camera.hpp"

#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/core/persistence.hpp>
#include <sstream>

namespace vision {
namespace {

bool finite_all(std::initializer_list<double> values) {
  for (double v : values)
    if (!std::isfinite(v)) return false;
  return true;
}

std::string lower_extension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos) return "";
  std::string ext = path.substr(dot + 1);
  for (auto& c : ext)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

[[noreturn]] void fail(const std::string& path, const std::string& key, const std::string& what) {
  throw CalibrationError("calibration file '" + path + "': key '" + key + "' " + what);
}

int read_int(const cv::FileNode& root, const std::string& path, const std::string& key) {
  const cv::FileNode n = root[key];
  if (n.empty()) fail(path, key, "is missing (expected a positive integer)");
  if (!n.isInt()) fail(path, key, "must be a positive integer");
  const int v = static_cast<int>(n);
  if (v <= 0) fail(path, key, "must be a positive integer, got " + std::to_string(v));
  return v;
}

// A calibration matrix is at most 3x3 (or 1x14 coefficients): rows and cols
// are bounded before OpenCV allocates the matrix they declare (a file declaring 10^5 x 10^5 would
// otherwise take 80 GB; found by fuzzing).
constexpr int kMaxMatrixSide = 16;
void check_matrix_shape(const cv::FileNode& n, const std::string& path, const std::string& key) {
  if (!n["rows"].isInt() || !n["cols"].isInt()) fail(path, key, "must give integer rows and cols");
  const int rows = static_cast<int>(n["rows"]), cols = static_cast<int>(n["cols"]);
  if (rows < 1 || cols < 1 || rows > kMaxMatrixSide || cols > kMaxMatrixSide)
    fail(path, key,
         "declares rows x cols = " + std::to_string(rows) + "x" + std::to_string(cols) +
             "; expected 1 to " + std::to_string(kMaxMatrixSide) + " of each");
}

// Reads a numeric matrix stored either as an OpenCV matrix (`!!opencv-matrix`
// or XML `type_id="opencv-matrix"`) or as a ROS map {rows, cols, data}.
// Returns the values row-major and the shape.
std::vector<double> read_matrix(const cv::FileNode& root, const std::string& path,
                                const std::string& key, int* rows, int* cols) {
  const cv::FileNode n = root[key];
  if (n.empty()) fail(path, key, "is missing");
  std::vector<double> values;
  if (n.isMap() && !n["dt"].empty()) {
    check_matrix_shape(n, path, key);
    cv::Mat m;
    try {
      n >> m;
    } catch (const cv::Exception& e) {
      fail(path, key, std::string("is not a readable matrix: ") + e.what());
    }
    if (m.empty()) fail(path, key, "is an empty matrix");
    m.convertTo(m, CV_64F);
    *rows = m.rows;
    *cols = m.cols;
    values.assign(m.begin<double>(), m.end<double>());
  } else if (n.isMap() && !n["data"].empty()) {
    check_matrix_shape(n, path, key);
    *rows = static_cast<int>(n["rows"]);
    *cols = static_cast<int>(n["cols"]);
    const cv::FileNode data = n["data"];
    if (!data.isSeq()) fail(path, key, "data must be a sequence of numbers");
    for (const auto& item : data) {
      if (!item.isReal() && !item.isInt())
        fail(path, key, "data holds a value that is not a number");
      values.push_back(static_cast<double>(item));
    }
    if (static_cast<int>(values.size()) != *rows * *cols)
      fail(path, key,
           "has " + std::to_string(values.size()) +
               " values but rows x cols = " + std::to_string(*rows) + "x" + std::to_string(*cols));
  } else if (n.isSeq()) {
    for (const auto& item : n) {
      if (!item.isReal() && !item.isInt()) fail(path, key, "holds a value that is not a number");
      values.push_back(static_cast<double>(item));
    }
    *rows = 1;
    *cols = static_cast<int>(values.size());
  } else {
    fail(path, key, "is not a matrix (expected an OpenCV matrix or {rows, cols, data})");
  }
  for (double v : values)
    if (!std::isfinite(v)) fail(path, key, "holds a value that is not finite");
  return values;
}

// The bounds of a calibration file: OpenCV's FileStorage parsers recurse
// once per nesting level and would exhaust the stack on a file nested
// thousands of levels deep; a calibration nests 3 levels and is a few KiB.
constexpr std::size_t kMaxCalibrationBytes = 1u << 20;
constexpr int kMaxCalibrationDepth = 32;
constexpr std::size_t kMaxIndentColumns = 256;

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

// YAML: flow collections ([ {) nest by brackets, block collections by the
// indentation and the "- " of each line; both are bounded. Brackets inside
// quoted scalars and comments do not count.
void check_yaml_nesting(const std::string& path, const std::string& text) {
  int depth = 0, line = 1;
  std::size_t column = 0;
  bool line_start = true, comment = false;
  char quote = 0;
  for (const char c : text) {
    if (c == '\n') {
      ++line;
      column = 0;
      line_start = true;
      comment = false;
      continue;
    }
    if (line_start && (c == ' ' || c == '-' || c == '\t')) {
      if (++column > kMaxIndentColumns)
        too_deep(path, line,
                 "indented more than " + std::to_string(kMaxIndentColumns) + " columns");
      continue;
    }
    line_start = false;
    if (comment) continue;
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '#') {
      comment = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxCalibrationDepth)
        too_deep(path, line,
                 "flow collections nested more than " + std::to_string(kMaxCalibrationDepth) +
                     " levels deep");
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
}

// XML: elements nest by start tags; <?...?>, <!...> and empty-element tags
// do not open a level.
void check_xml_nesting(const std::string& path, const std::string& text) {
  int depth = 0, line = 1;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\n') ++line;
    if (text[i] != '<' || i + 1 >= text.size()) continue;
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

}  // namespace

Camera::Camera(const Intrinsics& intrinsics, const Distortion& distortion, int width_px,
               int height_px)
    : intrinsics_(intrinsics), distortion_(distortion), width_px_(width_px), height_px_(height_px) {
  if (!finite_all({intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy}) ||
      intrinsics.fx <= 0 || intrinsics.fy <= 0)
    throw std::invalid_argument(
        "camera intrinsics: fx and fy must be finite and > 0, cx and cy finite");
  if (!finite_all({distortion.k1, distortion.k2, distortion.p1, distortion.p2, distortion.k3}))
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

  // OpenCV's YAML reader insists on its "%YAML:1.0" header; ROS camera_info
  // files are plain YAML, so give them one.
  const bool xml = text.compare(0, 5, "<?xml") == 0 || lower_extension(path) == "xml";
  if (xml)
    check_xml_nesting(path, text);
  else
    check_yaml_nesting(path, text);
  int flags = cv::FileStorage::READ | cv::FileStorage::MEMORY;
  if (xml) {
    flags |= cv::FileStorage::FORMAT_XML;
  } else {
    flags |= cv::FileStorage::FORMAT_YAML;
    if (text.compare(0, 5, "%YAML") != 0) text = "%YAML:1.0\n---\n" + text;
  }

  cv::FileStorage fs;
  try {
    fs.open(text, flags);
  } catch (const cv::Exception& e) {
    throw CalibrationError("calibration file '" + path +
                           "': not a YAML/XML calibration: " + e.what());
  }
  if (!fs.isOpened())
    throw CalibrationError("calibration file '" + path + "': not a YAML/XML calibration");
  const cv::FileNode root = fs.root();
  // FileNode::operator[] asserts a map: a file whose top level is a list or
  // a scalar is refused here, not by an OpenCV assertion.
  if (!root.isMap())
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

  const cv::FileNode model = root["distortion_model"];
  if (!model.empty()) {
    const std::string name = static_cast<std::string>(model);
    if (name != "plumb_bob" && name != "rational_polynomial")
      fail(path, "distortion_model", "'" + name + "' is not supported (expected plumb_bob)");
  }
  const auto d = read_matrix(root, path, "distortion_coefficients", &rows, &cols);
  if ((rows != 1 && cols != 1) || d.size() < 4)
    fail(path, "distortion_coefficients",
         "must be a vector of 4, 5 or more values (k1 k2 p1 p2 [k3 ...])");
  for (size_t i = 5; i < d.size(); ++i)
    if (d[i] != 0)
      fail(path, "distortion_coefficients",
           "has a non-zero term past k3 (rational or thin-prism model), which this camera model "
           "does not represent");
  const Distortion dist{d[0], d[1], d[2], d[3], d.size() > 4 ? d[4] : 0.0};
  return Camera({k[0], k[4], k[2], k[5]}, dist, width, height);
}

void Camera::save(const std::string& path) const {
  cv::FileStorage fs(path, cv::FileStorage::WRITE);
  if (!fs.isOpened()) throw CalibrationError("calibration file '" + path + "': cannot be written");
  fs << "image_width" << width_px_ << "image_height" << height_px_;
  fs << "camera_matrix" << camera_matrix_cv() << "distortion_coefficients" << distortion_cv();
}

bool Camera::has_distortion() const {
  const auto& d = distortion_;
  return d.k1 != 0 || d.k2 != 0 || d.p1 != 0 || d.p2 != 0 || d.k3 != 0;
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
  return (cv::Mat_<double>(1, 5) << d.k1, d.k2, d.p1, d.p2, d.k3);
}

Eigen::Vector2d Camera::project(const Eigen::Vector3d& p_cam) const {
  return distort_normalized(p_cam.head<2>() / p_cam.z());
}

Eigen::Vector2d Camera::distort_normalized(const Eigen::Vector2d& xy) const {
  const auto& d = distortion_;
  const double x = xy.x(), y = xy.y();
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  const double xd = x * radial + 2 * d.p1 * x * y + d.p2 * (r2 + 2 * x * x);
  const double yd = y * radial + d.p1 * (r2 + 2 * y * y) + 2 * d.p2 * x * y;
  return {intrinsics_.fx * xd + intrinsics_.cx, intrinsics_.fy * yd + intrinsics_.cy};
}

Eigen::Matrix2d Camera::distort_jacobian(const Eigen::Vector2d& xy) const {
  const auto& d = distortion_;
  const double x = xy.x(), y = xy.y();
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  // d(radial)/d(r2), and d(r2)/dx = 2x, d(r2)/dy = 2y.
  const double dradial = d.k1 + r2 * (2 * d.k2 + 3 * d.k3 * r2);
  Eigen::Matrix2d j;
  j(0, 0) = radial + x * dradial * 2 * x + 2 * d.p1 * y + d.p2 * 6 * x;
  j(0, 1) = x * dradial * 2 * y + 2 * d.p1 * x + d.p2 * 2 * y;
  j(1, 0) = y * dradial * 2 * x + d.p1 * 2 * x + 2 * d.p2 * y;
  j(1, 1) = radial + y * dradial * 2 * y + d.p1 * 6 * y + 2 * d.p2 * x;
  j.row(0) *= intrinsics_.fx;
  j.row(1) *= intrinsics_.fy;
  return j;
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
