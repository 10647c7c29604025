// Reading image files for the detector (`rig detect`, replayed frames).
#pragma once

#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

namespace vision {

// An image file that cannot be used: missing, empty, truncated, or not an
// image. The message names the file and what is wrong with it.
class ImageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads an image file as stored (8- or 16-bit, grey or colour, with or without
// alpha), for Detector::detect, which converts it. Formats: whatever OpenCV's
// imgcodecs decodes (PNG, JPEG, TIFF, PGM/PPM, BMP, ...). PNG and JPEG files are
// also checked for their end marker (IEND chunk, EOI marker), because their
// decoders return a partly grey image, not an error, when the file is cut short.
// Throws ImageError naming `path` when the file does not exist or cannot be
// read, is empty, is truncated, or does not decode.
cv::Mat read_image(const std::string& path);

}  // namespace vision
