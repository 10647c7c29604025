#include "vision/detector_image.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>

namespace vision {
namespace {

// The data ends with the format's end marker (formats whose decoders accept
// truncated data silently); true for other formats.
bool has_end_marker(const std::vector<std::uint8_t>& b, const std::string& format) {
  if (format == "PNG") {
    // The last chunk is IEND: length 0, type "IEND", CRC (12 bytes).
    static const std::uint8_t iend[] = {0, 0, 0, 0, 'I', 'E', 'N', 'D'};
    return b.size() >= 12 && std::equal(std::begin(iend), std::end(iend), b.end() - 12);
  }
  if (format == "JPEG") {
    // EOI (FF D9), possibly followed by padding some writers append.
    const size_t from = b.size() > 64 ? b.size() - 64 : 0;
    for (size_t i = b.size() - 1; i > from; --i)
      if (b[i - 1] == 0xFF && b[i] == 0xD9) return true;
    return false;
  }
  return true;
}

}  // namespace

cv::Mat decode_image(const std::vector<std::uint8_t>& bytes, int imread_flags,
                     const std::string& name) {
  if (bytes.empty()) throw ImageError(name + ": is empty (0 bytes)");
  const ImageHeader header = read_image_header(bytes.data(), bytes.size(), name);
  if (!has_end_marker(bytes, header.format))
    throw ImageError(name + ": is truncated (" + header.format +
                     " data ends before its end marker)");
  cv::Mat image;
  try {
    image = cv::imdecode(bytes, imread_flags);
  } catch (const cv::Exception& e) {
    throw ImageError(name + ": cannot be decoded: " + e.what());
  }
  if (image.empty())
    throw ImageError(name + ": its " + header.format + " data does not decode (damaged)");
  return image;
}

cv::Mat read_image(const std::string& path) {
  const std::string name = "image '" + path + "'";
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
    throw ImageError(
        name + ": is " +
        (std::filesystem::is_directory(status) ? "a directory" : "not a regular file") +
        "; expected an image file (PNG, JPEG, TIFF, PGM/PPM or BMP)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ImageError(name + ": cannot be opened (missing or unreadable)");
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  return decode_image(bytes, cv::IMREAD_UNCHANGED, name);
}

}  // namespace vision
