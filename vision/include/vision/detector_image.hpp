// Reading image files for the detector (`rig detect`, replayed frames, the
// report's frame pictures): what an image declares is checked before a
// decoder sees it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>

namespace vision {

// An image file that cannot be used: missing, empty, truncated, too large,
// or not an image. The message names the file and what is wrong with it.
class ImageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The largest image rig decodes: 2^28 pixels (268 Mpx; the largest industrial
// sensors are about 150 Mpx) and 1 GiB once decoded. A file that declares more
// is refused before decoding, so that a small compressed file cannot make the
// decoder allocate and fill gigabytes.
constexpr std::int64_t kMaxImagePixels = std::int64_t{1} << 28;
constexpr std::int64_t kMaxImageBytes = std::int64_t{1} << 30;

// What an image file's header declares, read without decoding it.
struct ImageHeader {
  std::string format;      // "PNG", "JPEG", "TIFF", "PNM" or "BMP"
  std::int64_t width = 0;  // pixels
  std::int64_t height = 0;
  int channels = 0;          // as decoded unchanged: at most 4
  int bytes_per_sample = 0;  // 1 or 2
  std::int64_t decoded_bytes() const { return width * height * channels * bytes_per_sample; }
};

// Reads the header of a PNG (IHDR), JPEG (the first SOF marker), TIFF (the
// first IFD), PGM/PPM/PBM/PAM or BMP file held in the `size` bytes at `data`
// (a whole file, or at least its header). `name` describes the
// input in messages (e.g. "image 'a.png'"). Throws ImageError naming `name` when
// the format is none of these, when the header is cut short or malformed, when
// a dimension is below 1, or when the declared image exceeds kMaxImagePixels or
// kMaxImageBytes.
ImageHeader read_image_header(const std::uint8_t* data, std::size_t size, const std::string& name);

// Decodes the `size` image bytes at `data` with vision::imdecode(`imread_flags`)
// after read_image_header has accepted them; PNG and JPEG data must also end
// with their end marker (IEND chunk, EOI marker), because their decoders
// return a partly grey image, not an error, when the data is cut short.
// Throws ImageError naming `name` when the bytes are empty, refused by
// read_image_header, truncated, or do not decode; ImageCodecsUnavailable
// when the decoders cannot be loaded (vision/image_codecs.hpp).
cv::Mat decode_image(const std::uint8_t* data, std::size_t size, int imread_flags,
                     const std::string& name);

// Reads an image file: decode_image on its bytes with `imread_flags` (by
// default as stored: 8- or 16-bit, grey or colour, with or without alpha, for
// Detector::detect, which converts it). Throws ImageError naming `path` when
// the file does not exist, is not a regular file or cannot be read, or when
// decode_image refuses it.
cv::Mat read_image(const std::string& path, int imread_flags = cv::IMREAD_UNCHANGED);

}  // namespace vision
