// Image headers are read, and bounded, before any decoder sees the data.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "vision/detector_image.hpp"
#include "vision/image_codecs.hpp"

namespace {

using Bytes = std::vector<std::uint8_t>;

std::string header_error(const Bytes& bytes) {
  try {
    vision::read_image_header(bytes.data(), bytes.size(), "image 'x'");
  } catch (const vision::ImageError& e) {
    return e.what();
  }
  return "(accepted)";
}

Bytes text(const std::string& s) {
  return Bytes(s.begin(), s.end());
}

// A PNG signature and an IHDR chunk (CRC not checked by the header reader).
Bytes png_ihdr(std::uint32_t width, std::uint32_t height, int depth, int colour) {
  Bytes b = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A, 0, 0, 0, 13, 'I', 'H', 'D', 'R'};
  for (std::uint32_t v : {width, height})
    for (int shift = 24; shift >= 0; shift -= 8)
      b.push_back(static_cast<std::uint8_t>(v >> shift));
  for (int v : {depth, colour, 0, 0, 0, 0, 0, 0, 0})
    b.push_back(static_cast<std::uint8_t>(v));
  return b;
}

// A little-endian TIFF whose first IFD holds these LONG tags: {tag, count,
// value or offset}.
Bytes tiff_of(std::initializer_list<std::array<std::uint32_t, 3>> tags) {
  Bytes b = {'I', 'I', 42, 0, 8, 0, 0, 0, static_cast<std::uint8_t>(tags.size()), 0};
  for (const auto& [tag, count, value] : tags)
    for (const auto& [v, bytes] : {std::pair{tag, 2}, {4u, 2}, {count, 4}, {value, 4}})
      for (int i = 0; i < bytes; ++i)
        b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  return b;
}

// Every format rig reads, written by OpenCV: the header declares the size
// the data decodes to, and at least the bytes it decodes to (the bound
// decode_image relies on; BMP is bounded at 4 channels whatever it holds).
TEST(ImageHeader, EveryFormatDeclaresWhatItDecodesTo) {
  cv::Mat grey(23, 37, CV_8UC1), grey16(23, 37, CV_16UC1), colour(23, 37, CV_8UC3);
  cv::randu(grey, 0, 255);
  cv::randu(grey16, 0, 65535);
  cv::randu(colour, 0, 255);
  const struct {
    const char* ext;
    const cv::Mat* image;
  } cases[] = {{".png", &grey},   {".png", &grey16}, {".png", &colour}, {".jpg", &grey},
               {".jpg", &colour}, {".tif", &grey16}, {".tif", &colour}, {".pgm", &grey},
               {".pgm", &grey16}, {".ppm", &colour}, {".pbm", &grey},   {".pam", &colour},
               {".bmp", &grey},   {".bmp", &colour}};
  for (const auto& c : cases) {
    Bytes bytes;
    ASSERT_TRUE(vision::imencode(c.ext, *c.image, bytes)) << c.ext;
    const cv::Mat decoded = vision::imdecode(bytes, cv::IMREAD_UNCHANGED);
    const std::string what = std::string(c.ext) + " of type " + std::to_string(c.image->type());
    ASSERT_FALSE(decoded.empty()) << what;
    const vision::ImageHeader h = vision::read_image_header(bytes.data(), bytes.size(), what);
    EXPECT_EQ(h.width, decoded.cols) << what;
    EXPECT_EQ(h.height, decoded.rows) << what;
    EXPECT_GE(h.decoded_bytes(), static_cast<std::int64_t>(decoded.total() * decoded.elemSize()))
        << what;
    if (h.format != "BMP") {
      EXPECT_EQ(h.channels, decoded.channels()) << what;
      EXPECT_EQ(h.bytes_per_sample, static_cast<int>(decoded.elemSize1())) << what;
    }
    EXPECT_EQ(vision::decode_image(bytes.data(), bytes.size(), cv::IMREAD_UNCHANGED, what).size(),
              decoded.size());
  }
}

// A 0.3 MB PNG that inflates to 269 MB of pixels: refused from its header,
// before the decoder allocates or fills anything. (Without the bound,
// decode_image returns the 16,400 x 16,400 image.)
TEST(ImageHeader, AFileDeclaringMoreThanTheLimitIsRefusedBeforeDecoding) {
  Bytes bomb;
  {
    const cv::Mat zeros(16400, 16400, CV_8UC1, cv::Scalar(0));
    ASSERT_TRUE(vision::imencode(".png", zeros, bomb));
  }
  ASSERT_GT(16400LL * 16400, vision::kMaxImagePixels);
  try {
    vision::decode_image(bomb.data(), bomb.size(), cv::IMREAD_UNCHANGED, "image 'bomb.png'");
    FAIL() << "a " << bomb.size() << "-byte PNG of 16400 x 16400 pixels was decoded";
  } catch (const vision::ImageError& e) {
    EXPECT_STREQ(e.what(),
                 "image 'bomb.png': PNG header declares 16400 x 16400 pixels; expected at most "
                 "268 Mpx and 1 GiB decoded");
  }
  // 2^28 pixels exactly is accepted; 8192 x 8192 RGBA at 16 bits (512 MiB) is
  // within the byte bound, 12000 x 12000 (1.07 GiB) is not.
  EXPECT_EQ(header_error(png_ihdr(16384, 16384, 8, 0)), "(accepted)");
  EXPECT_EQ(header_error(png_ihdr(8192, 8192, 16, 6)), "(accepted)");
  EXPECT_NE(header_error(png_ihdr(12000, 12000, 16, 6)).find("declares 12000 x 12000"),
            std::string::npos);
  // Sides whose product would overflow 64 bits are refused, not wrapped.
  EXPECT_NE(header_error(png_ihdr(0xFFFFFFFF, 0xFFFFFFFF, 8, 0)).find("4294967295 x 4294967295"),
            std::string::npos);
  EXPECT_NE(header_error(tiff_of({{256, 1, 70000}, {257, 1, 70000}}))
                .find("TIFF header declares 70000 x 70000"),
            std::string::npos);
  EXPECT_NE(header_error(text("P5 4000000000 4000000000 255\n")).find("4000000000 x 4000000000"),
            std::string::npos);
}

TEST(ImageHeader, MalformedHeadersAreRefusedNamingTheInputAndTheFormat) {
  const Bytes png_signature = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  const struct {
    Bytes bytes;
    const char* expected;
  } cases[] = {
      {png_signature, "image 'x': PNG header does not start with a 13-byte IHDR chunk"},
      {png_ihdr(37, 23, 8, 5), "image 'x': PNG header has colour type 5; expected 0, 2, 3, 4 or 6"},
      {png_ihdr(37, 23, 12, 0),
       "image 'x': PNG header has bit depth 12; expected 1, 2, 4, 8 or 16"},
      {png_ihdr(0, 23, 8, 0),
       "image 'x': PNG header declares 0 x 23 pixels; expected at least 1 x 1"},
      {{0xFF, 0xD8, 0xFF, 0xDA, 0, 8},
       "image 'x': JPEG header reaches its scan before a frame header (SOF marker)"},
      {{0xFF, 0xD8, 0xFF, 0xE0, 0}, "image 'x': JPEG header has a marker segment cut short"},
      {{0xFF, 0xD8, 0xFF, 0xC0, 0, 17, 8, 0},
       "image 'x': JPEG header has a frame header cut short"},
      {{0xFF, 0xD8, 0xFF, 0xC0, 0, 8, 8, 0, 23, 0, 37, 9},
       "image 'x': JPEG header declares 9 components; expected 1 to 4"},
      {{0xFF, 0xD8, 0x00},
       "image 'x': JPEG header ends or breaks off before its frame header "
       "(SOF marker)"},
      {{'I', 'I', 42, 0, 0xE8, 0x03, 0, 0},
       "image 'x': TIFF header points to a first IFD beyond the end of the data"},
      {tiff_of({{256, 1, 4}, {257, 1, 4}, {277, 1, 0}}),
       "image 'x': TIFF header declares 0 samples per pixel; expected 1 to 4"},
      {tiff_of({{256, 1, 4}, {257, 3, 900}}), "image 'x': TIFF header has a tag value cut short"},
      {text("P5 12x 3 255\n"), "image 'x': PNM header has a width '12x'; expected a whole number"},
      {text("P5\n# a comment 9 9\n12"),
       "image 'x': PNM header has a height ''; expected a whole number"},
      {text("P7\nWIDTH 4\nHEIGHT 4\n"), "image 'x': PAM header ends before ENDHDR"},
      {text("BM\x10\0"), "image 'x': BMP header ends before its info header"},
      {text("GIF89a"),
       "image 'x': is not an image rig reads (expected PNG, JPEG, TIFF, PGM/PPM or BMP)"},
      {{}, "image 'x': is not an image rig reads (expected PNG, JPEG, TIFF, PGM/PPM or BMP)"},
  };
  for (const auto& c : cases)
    EXPECT_EQ(header_error(c.bytes), c.expected);
  // Only the four tags of the size are read: another tag's values may lie
  // anywhere (here StripOffsets, 3 values at an offset past the end).
  EXPECT_EQ(header_error(tiff_of({{256, 1, 4}, {257, 1, 4}, {273, 3, 900}})), "(accepted)");
}

}  // namespace
