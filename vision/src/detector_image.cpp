#include "vision/detector_image.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <vector>

#include "vision/image_codecs.hpp"

namespace vision {
namespace {

// The data ends with the format's end marker (formats whose decoders accept
// truncated data silently); true for other formats.
bool has_end_marker(const std::uint8_t* b, std::size_t size, const std::string& format) {
  if (format == "PNG") {
    // The last chunk is IEND: length 0, type "IEND", CRC (12 bytes).
    static const std::uint8_t iend[] = {0, 0, 0, 0, 'I', 'E', 'N', 'D'};
    return size >= 12 && std::equal(std::begin(iend), std::end(iend), b + size - 12);
  }
  if (format == "JPEG") {
    // EOI (FF D9), possibly followed by padding some writers append.
    const size_t from = size > 64 ? size - 64 : 0;
    for (size_t i = size - 1; i > from; --i)
      if (b[i - 1] == 0xFF && b[i] == 0xD9) return true;
    return false;
  }
  return true;
}

}  // namespace

cv::Mat decode_image(const std::uint8_t* data, std::size_t size, int imread_flags,
                     const std::string& name) {
  if (data == nullptr || size == 0) throw ImageError(name + ": is empty (0 bytes)");
  if (size > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw ImageError(name + ": is " + std::to_string(size >> 20) +
                     " MiB; expected an image file under 2 GiB");
  const ImageHeader header = read_image_header(data, size, name);
  if (!has_end_marker(data, size, header.format))
    throw ImageError(name + ": is truncated (" + header.format +
                     " data ends before its end marker)");
  cv::Mat image;
  try {
    // A header over the bytes, not a copy: imdecode only reads them.
    const cv::Mat bytes(1, static_cast<int>(size), CV_8UC1, const_cast<std::uint8_t*>(data));
    image = vision::imdecode(bytes, imread_flags);
  } catch (const cv::Exception& e) {
    throw ImageError(name + ": cannot be decoded: " + e.what());
  }
  if (image.empty())
    throw ImageError(name + ": its " + header.format + " data does not decode (damaged)");
  return image;
}

cv::Mat read_image(const std::string& path, int imread_flags) {
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
  return decode_image(bytes.data(), bytes.size(), imread_flags, name);
}

}  // namespace vision
