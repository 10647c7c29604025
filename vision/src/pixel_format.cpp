// Camera buffers to detector images (see vision/pixel_format.hpp).
#include "vision/pixel_format.hpp"

#include <cstdio>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "vision/detector_image.hpp"
#include "vision/image_codecs.hpp"

namespace vision {
namespace {

struct NamedFormat {
  const char* name;
  uint32_t code;
  int bits;
};

constexpr NamedFormat kFormats[] = {
    {"Mono8", pfnc::kMono8, 8},    {"Mono10", pfnc::kMono10, 10},
    {"Mono12", pfnc::kMono12, 12}, {"Mono12Packed", pfnc::kMono12Packed, 12},
    {"Mono16", pfnc::kMono16, 16}, {"BayerRG8", pfnc::kBayerRG8, 8},
};

const NamedFormat* find_format(uint32_t code) {
  for (const NamedFormat& f : kFormats)
    if (f.code == code) return &f;
  return nullptr;
}

std::string hex(uint32_t code) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%08x", static_cast<unsigned>(code));
  return text;
}

std::string known_names() {
  std::string names;
  for (const NamedFormat& f : kFormats)
    names += (names.empty() ? "" : ", ") + std::string(f.name);
  return names;
}

// Two pixels in three bytes, GigE Vision's Mono12Packed (see the header),
// one stream over the whole frame (a row of odd width ends mid-group).
cv::Mat unpack_mono12_packed(const uint8_t* in, int width, int height) {
  cv::Mat out(height, width, CV_16UC1);
  const size_t n = static_cast<size_t>(width) * static_cast<size_t>(height);
  auto* o = out.ptr<uint16_t>();
  for (size_t i = 0; i < n; i += 2, in += 3) {
    o[i] = static_cast<uint16_t>(in[0] << 4 | (in[1] & 0x0F));
    if (i + 1 < n) o[i + 1] = static_cast<uint16_t>(in[2] << 4 | in[1] >> 4);
  }
  return out;
}

// Little-endian 16-bit words, masked to the format's bits (a camera may
// leave garbage in the padding bits; they carry no measurement).
cv::Mat read_mono16(const uint8_t* in, int width, int height, int bits) {
  cv::Mat out(height, width, CV_16UC1);
  const uint16_t mask = static_cast<uint16_t>((1u << bits) - 1);
  const size_t n = static_cast<size_t>(width) * static_cast<size_t>(height);
  auto* o = out.ptr<uint16_t>();
  for (size_t i = 0; i < n; ++i)
    o[i] = static_cast<uint16_t>((in[2 * i] | in[2 * i + 1] << 8) & mask);
  return out;
}

}  // namespace

std::string pixel_format_name(uint32_t pfnc_code) {
  const NamedFormat* f = find_format(pfnc_code);
  return f != nullptr ? f->name : hex(pfnc_code);
}

uint32_t pixel_format_code(const std::string& name) {
  for (const NamedFormat& f : kFormats)
    if (name == f.name) return f.code;
  throw PixelFormatError("pixel format \"" + name + "\": expected one of " + known_names());
}

bool is_readable_pixel_format(uint32_t pfnc_code) {
  return find_format(pfnc_code) != nullptr;
}

std::string readable_pixel_formats() {
  return known_names();
}

int significant_bits(uint32_t pfnc_code) {
  const NamedFormat* f = find_format(pfnc_code);
  if (f == nullptr)
    throw PixelFormatError("pixel format " + hex(pfnc_code) +
                           " is not one the capture path reads (" + known_names() + ")");
  return f->bits;
}

size_t payload_bytes(uint32_t pfnc_code, int width, int height) {
  const size_t w = static_cast<size_t>(width), h = static_cast<size_t>(height);
  if (pfnc_code == pfnc::kMono12Packed) return (w * h + 1) / 2 * 3;
  const size_t bits = (pfnc_code >> 16) & 0xFF;
  return w * h * bits / 8;
}

cv::Mat gige_payload_to_image(const void* data, size_t size, int width, int height,
                              uint32_t pfnc_code) {
  const int bits = significant_bits(pfnc_code);  // throws for unknown formats
  const bool bayer = pfnc_code == pfnc::kBayerRG8;
  if (width < (bayer ? 2 : 1) || height < (bayer ? 2 : 1))
    throw PixelFormatError(pixel_format_name(pfnc_code) + " frame of " + std::to_string(width) +
                           " x " + std::to_string(height) + " pixels: expected at least " +
                           (bayer ? "2 x 2" : "1 x 1"));
  const size_t needed = payload_bytes(pfnc_code, width, height);
  if (data == nullptr || size < needed)
    throw PixelFormatError(pixel_format_name(pfnc_code) + " frame of " + std::to_string(width) +
                           " x " + std::to_string(height) + ": " + std::to_string(size) +
                           " bytes, expected " + std::to_string(needed));
  const auto* in = static_cast<const uint8_t*>(data);
  switch (pfnc_code) {
    case pfnc::kMono8:
      return cv::Mat(height, width, CV_8UC1, const_cast<uint8_t*>(in)).clone();
    case pfnc::kMono12Packed:
      return unpack_mono12_packed(in, width, height);
    case pfnc::kBayerRG8: {
      cv::Mat gray;
      cv::cvtColor(cv::Mat(height, width, CV_8UC1, const_cast<uint8_t*>(in)), gray,
                   cv::COLOR_BayerBG2GRAY);
      return gray;
    }
    default:  // Mono10, Mono12, Mono16
      return read_mono16(in, width, height, bits);
  }
}

std::string fourcc_name(uint32_t code) {
  std::string name(4, ' ');
  for (int k = 0; k < 4; ++k) {
    const char c = static_cast<char>((code >> (8 * k)) & 0xFF);
    name[static_cast<size_t>(k)] = (c >= 32 && c < 127) ? c : '?';
  }
  return name;
}

cv::Mat v4l2_buffer_to_image(const void* data, size_t used, int width, int height,
                             size_t bytes_per_line, uint32_t fourcc_code) {
  const std::string who = "V4L2 " + fourcc_name(fourcc_code) + " frame of " +
                          std::to_string(width) + " x " + std::to_string(height);
  if (width < 1 || height < 1) throw PixelFormatError(who + ": expected at least 1 x 1 pixels");
  const auto* in = static_cast<const uint8_t*>(data);
  if (fourcc_code == fourcc::kMjpeg) {
    if (in == nullptr || used == 0) throw PixelFormatError(who + ": empty buffer");
    // The size the JPEG declares must be the negotiated one before it is
    // decoded: a damaged frame must not make the decoder allocate more.
    try {
      const ImageHeader h = read_image_header(in, used, who);
      if (h.format != "JPEG" || h.width != width || h.height != height)
        throw PixelFormatError(who + ": the buffer's " + h.format + " declares " +
                               std::to_string(h.width) + " x " + std::to_string(h.height) +
                               " pixels");
    } catch (const ImageError& e) {
      throw PixelFormatError(std::string(e.what()) + " (the buffer does not decode as a JPEG)");
    }
    const cv::Mat bytes(1, static_cast<int>(used), CV_8UC1, const_cast<uint8_t*>(in));
    cv::Mat gray = vision::imdecode(bytes, cv::IMREAD_GRAYSCALE);
    if (gray.empty()) throw PixelFormatError(who + ": the buffer does not decode as a JPEG");
    return gray;
  }
  int pixel_bytes = 0, type = -1;
  if (fourcc_code == fourcc::kGrey) {
    pixel_bytes = 1, type = CV_8UC1;
  } else if (fourcc_code == fourcc::kY16) {
    pixel_bytes = 2, type = CV_16UC1;
  } else if (fourcc_code == fourcc::kYuyv) {
    pixel_bytes = 2, type = CV_8UC2;
  } else {
    throw PixelFormatError(who + ": not a format the capture path reads (GREY, Y16, YUYV, MJPG)");
  }
  const size_t row_bytes = static_cast<size_t>(width) * static_cast<size_t>(pixel_bytes);
  const size_t stride = bytes_per_line > 0 ? bytes_per_line : row_bytes;
  const size_t needed = stride * static_cast<size_t>(height - 1) + row_bytes;
  if (in == nullptr || stride < row_bytes || used < needed)
    throw PixelFormatError(who + ": " + std::to_string(used) + " bytes with rows of " +
                           std::to_string(stride) + ", expected at least " +
                           std::to_string(needed));
  const cv::Mat view(height, width, type, const_cast<uint8_t*>(in), stride);
  if (fourcc_code != fourcc::kYuyv) return view.clone();
  cv::Mat luma;
  cv::extractChannel(view, luma, 0);  // Y0 U Y1 V: channel 0 of each 2-byte pixel is its Y
  return luma;
}

}  // namespace vision
