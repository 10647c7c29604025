// Image bytes (a file given to `rig detect`, a replayed or reported frame):
// decoded, or refused with vision::ImageError. The header is read and bounded
// first (vision::read_image_header), then OpenCV's decoders run on what it
// accepted.
#include <cstddef>
#include <cstdint>
#include <opencv2/imgcodecs.hpp>

#include "vision/detector_image.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)vision::decode_image(data, size, cv::IMREAD_UNCHANGED, "image 'fuzz input'");
  } catch (const vision::ImageError&) {
  }
  return 0;
}
