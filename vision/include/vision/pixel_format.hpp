// vision pixel formats: how a camera's buffer becomes the detector's image.
//
// GigE Vision cameras describe their pixels with PFNC codes (the GenICam
// Pixel Format Naming Convention; the 32-bit values of the PixelFormat
// feature and of the GVSP image leader). The conversions, chosen so that no
// information the camera measured is lost and nothing is invented:
//
//   Mono8         -> CV_8UC1, exactly the bytes on the wire.
//   Mono10        -> CV_16UC1, LSB-aligned 0 .. 1023: bit depth kept (two bytes
//                    a pixel, little-endian, the upper 6 bits zero).
//   Mono12        -> CV_16UC1, LSB-aligned 0 .. 4095: bit depth kept.
//   Mono12Packed  -> CV_16UC1, LSB-aligned 0 .. 4095, unpacked from GigE
//                    Vision's packing: two pixels in three bytes,
//                    B0 = P0[11:4], B1 = P1[3:0] << 4 | P0[3:0], B2 = P1[11:4]
//                    (not PFNC Mono12p, which packs LSB first), one stream
//                    over the frame's pixels in row order.
//   Mono16        -> CV_16UC1, 0 .. 65535.
//   BayerRG8      -> CV_8UC1 luminance: demosaiced by OpenCV's cvtColor
//                    (bilinear, COLOR_BayerBG2GRAY: OpenCV names a mosaic by
//                    the second row's second and third pixels, so GenICam's
//                    RGGB "BayerRG" is OpenCV's "BayerBG"), Y = 0.299 R +
//                    0.587 G + 0.114 B (ITU-R BT.601) per pixel.
//
// The detector (vision::to_gray8) takes a 16-bit image at its own range (a
// 12-bit image's brightest pixel, not 65535, maps to 255), so Mono10 and
// Mono12 reach it at the same contrast as Mono8; Frame::significant_bits
// tells how many bits the camera measured.
//
// V4L2 devices name their formats by fourcc: GREY (8-bit luma, kept), Y16
// (16-bit, kept), YUYV (4:2:2; the Y samples are the luma, kept, U and V
// dropped) and MJPG (each frame a JPEG; decoded by OpenCV's imdecode to 8-bit
// grey: a lossy format, the JPEG quantization is in the image).
#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

namespace vision {

// PFNC codes (GenICam SFNC / GigE Vision; the same values as Aravis's
// ARV_PIXEL_FORMAT_*): bits 16..23 hold the bits per pixel on the wire.
namespace pfnc {
constexpr uint32_t kMono8 = 0x01080001;
constexpr uint32_t kMono10 = 0x01100003;
constexpr uint32_t kMono12 = 0x01100005;
constexpr uint32_t kMono12Packed = 0x010C0006;
constexpr uint32_t kMono16 = 0x01100007;
constexpr uint32_t kBayerRG8 = 0x01080009;
}  // namespace pfnc

// A buffer that cannot become an image: an unknown format, or fewer bytes
// than its size needs. The message names the format and what was expected.
class PixelFormatError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// The GenICam name of a PFNC code ("Mono12Packed"), or "0x%08x" when it is
// not one the capture path reads.
std::string pixel_format_name(uint32_t pfnc_code);
// The PFNC code of a GenICam name; throws PixelFormatError naming it and the
// names the capture path reads when it is not one of them.
uint32_t pixel_format_code(const std::string& name);
// Whether gige_payload_to_image reads the format, and the list of those it
// reads ("Mono8, Mono10, ...") for messages.
bool is_readable_pixel_format(uint32_t pfnc_code);
std::string readable_pixel_formats();
// Bits the camera measured per pixel: 8, 10, 12 or 16 (8 for BayerRG8).
int significant_bits(uint32_t pfnc_code);
// Bytes one frame of width x height takes on the wire (Mono12Packed: 3 per
// pair of pixels, a last odd pixel taking a whole group).
size_t payload_bytes(uint32_t pfnc_code, int width, int height);

// Converts a GigE Vision image payload (rows packed, no padding) to the
// detector's image (see the table above). Preconditions: width, height > 0;
// BayerRG8 needs width, height >= 2. Throws PixelFormatError when the format
// is not one of the table's or `size` < payload_bytes().
cv::Mat gige_payload_to_image(const void* data, size_t size, int width, int height,
                              uint32_t pfnc_code);

// V4L2 fourccs the capture path reads (linux/videodev2.h's V4L2_PIX_FMT_*).
namespace fourcc {
constexpr uint32_t make(char a, char b, char c, char d) {
  return static_cast<uint32_t>(a) | static_cast<uint32_t>(b) << 8 | static_cast<uint32_t>(c) << 16 |
         static_cast<uint32_t>(d) << 24;
}
constexpr uint32_t kGrey = make('G', 'R', 'E', 'Y');
constexpr uint32_t kY16 = make('Y', '1', '6', ' ');
constexpr uint32_t kYuyv = make('Y', 'U', 'Y', 'V');
constexpr uint32_t kMjpeg = make('M', 'J', 'P', 'G');
}  // namespace fourcc

// Converts one V4L2 buffer to the detector's image: GREY -> CV_8UC1, Y16 ->
// CV_16UC1, YUYV -> CV_8UC1 (its Y samples), MJPG -> CV_8UC1 (decoded).
// `bytes_per_line` is the driver's row stride (0: rows packed); `used` the
// bytes the driver filled. Throws PixelFormatError naming the fourcc when it
// is not one of these, when the buffer is shorter than height rows, or when
// an MJPG frame's JPEG header does not declare width x height (checked before
// decoding) or its data does not decode.
cv::Mat v4l2_buffer_to_image(const void* data, size_t used, int width, int height,
                             size_t bytes_per_line, uint32_t fourcc_code);

// "GREY", "YUYV", ...: the four characters of a fourcc.
std::string fourcc_name(uint32_t fourcc_code);

}  // namespace vision
