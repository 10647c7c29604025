#include "vision/detector_image.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <vector>

namespace vision {
namespace {

bool starts_with(const std::vector<uchar>& b, std::initializer_list<uchar> magic) {
  if (b.size() < magic.size()) return false;
  return std::equal(magic.begin(), magic.end(), b.begin());
}

// The file ends with the format's end marker (formats whose decoders accept
// truncated data silently); true for other formats.
bool has_end_marker(const std::vector<uchar>& b, std::string* format) {
  if (starts_with(b, {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A})) {
    *format = "PNG";
    // The last chunk is IEND: length 0, type "IEND", CRC (12 bytes).
    static const uchar iend[] = {0, 0, 0, 0, 'I', 'E', 'N', 'D'};
    return b.size() >= 12 && std::equal(std::begin(iend), std::end(iend), b.end() - 12);
  }
  if (starts_with(b, {0xFF, 0xD8, 0xFF})) {
    *format = "JPEG";
    // EOI (FF D9), possibly followed by padding some writers append.
    const size_t from = b.size() > 64 ? b.size() - 64 : 0;
    for (size_t i = b.size() - 1; i > from; --i)
      if (b[i - 1] == 0xFF && b[i] == 0xD9) return true;
    return false;
  }
  return true;
}

}  // namespace

cv::Mat read_image(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
    throw ImageError(
        "image '" + path + "': is " +
        (std::filesystem::is_directory(status) ? "a directory" : "not a regular file") +
        "; expected an image file (PNG, JPEG, TIFF, PGM/PPM or BMP)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ImageError("image '" + path + "': cannot be opened (missing or unreadable)");
  const std::vector<uchar> bytes((std::istreambuf_iterator<char>(in)),
                                 std::istreambuf_iterator<char>());
  if (bytes.empty()) throw ImageError("image '" + path + "': is empty (0 bytes)");
  std::string format;
  if (!has_end_marker(bytes, &format))
    throw ImageError("image '" + path + "': is truncated (" + format +
                     " data ends before its end marker)");
  cv::Mat image;
  try {
    image = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw ImageError("image '" + path + "': cannot be decoded: " + e.what());
  }
  if (image.empty())
    throw ImageError("image '" + path + "': is not an image OpenCV can decode (expected PNG, " +
                     "JPEG, TIFF, PGM/PPM or BMP)");
  return image;
}

}  // namespace vision
