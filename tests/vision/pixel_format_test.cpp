// vision/pixel_format.hpp: every buffer layout the capture path reads, on
// buffers written by hand with known pixel values (so a swapped nibble, a
// wrong endianness or a Bayer phase off by one pixel changes the result).
#include "vision/pixel_format.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "vision/image_codecs.hpp"

namespace {

using vision::PixelFormatError;
namespace pfnc = vision::pfnc;
namespace fourcc = vision::fourcc;

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const PixelFormatError& e) {
    return e.what();
  }
  return "";
}

TEST(GigePixelFormat, Mono8IsTheBytesOnTheWire) {
  const std::vector<uint8_t> wire = {0, 1, 127, 128, 254, 255};
  const cv::Mat image = vision::gige_payload_to_image(wire.data(), wire.size(), 3, 2, pfnc::kMono8);
  ASSERT_EQ(image.type(), CV_8UC1);
  ASSERT_EQ(image.size(), cv::Size(3, 2));
  EXPECT_EQ(image.at<uint8_t>(0, 0), 0);
  EXPECT_EQ(image.at<uint8_t>(0, 2), 127);
  EXPECT_EQ(image.at<uint8_t>(1, 0), 128);
  EXPECT_EQ(image.at<uint8_t>(1, 2), 255);
  EXPECT_EQ(vision::significant_bits(pfnc::kMono8), 8);
}

// Little-endian words; the bits above the format's depth are padding a
// camera may fill with anything, and they are masked off.
TEST(GigePixelFormat, Mono10AndMono12KeepTheirBitsLsbAligned) {
  // 0x0000, 0x0001, 0x03FF (1023), 0xFE00 | 0x0155 (padding set, value 341).
  const std::vector<uint8_t> mono10 = {0x00, 0x00, 0x01, 0x00, 0xFF, 0x03, 0x55, 0xFD};
  const cv::Mat ten =
      vision::gige_payload_to_image(mono10.data(), mono10.size(), 4, 1, pfnc::kMono10);
  ASSERT_EQ(ten.type(), CV_16UC1);
  EXPECT_EQ(ten.at<uint16_t>(0, 0), 0);
  EXPECT_EQ(ten.at<uint16_t>(0, 1), 1);
  EXPECT_EQ(ten.at<uint16_t>(0, 2), 1023);
  EXPECT_EQ(ten.at<uint16_t>(0, 3), 0x155);
  // 4095, 0x0ABC, 0xF123 with padding -> 0x123, 2048.
  const std::vector<uint8_t> mono12 = {0xFF, 0x0F, 0xBC, 0x0A, 0x23, 0xF1, 0x00, 0x08};
  const cv::Mat twelve =
      vision::gige_payload_to_image(mono12.data(), mono12.size(), 2, 2, pfnc::kMono12);
  EXPECT_EQ(twelve.at<uint16_t>(0, 0), 4095);
  EXPECT_EQ(twelve.at<uint16_t>(0, 1), 0xABC);
  EXPECT_EQ(twelve.at<uint16_t>(1, 0), 0x123);
  EXPECT_EQ(twelve.at<uint16_t>(1, 1), 2048);
  EXPECT_EQ(vision::significant_bits(pfnc::kMono10), 10);
  EXPECT_EQ(vision::significant_bits(pfnc::kMono12), 12);
}

TEST(GigePixelFormat, Mono16IsLittleEndian) {
  const std::vector<uint8_t> wire = {0x34, 0x12, 0xFF, 0xFF};
  const cv::Mat image =
      vision::gige_payload_to_image(wire.data(), wire.size(), 2, 1, pfnc::kMono16);
  EXPECT_EQ(image.at<uint16_t>(0, 0), 0x1234);
  EXPECT_EQ(image.at<uint16_t>(0, 1), 0xFFFF);
}

// GigE Vision Mono12Packed: pixels 0x123 and 0xABC pack to B0 = 0x12 (P0
// bits 11..4), B1 = 0xC3 (P1 bits 3..0, then P0 bits 3..0), B2 = 0xAB (P1
// bits 11..4). A 3 x 1 frame: the last pixel takes a group of its own.
TEST(GigePixelFormat, Mono12PackedUnpacksTwoPixelsFromThreeBytes) {
  const std::vector<uint8_t> wire = {0x12, 0xC3, 0xAB, 0xFF, 0x0F, 0x00};
  EXPECT_EQ(vision::payload_bytes(pfnc::kMono12Packed, 3, 1), 6u);
  EXPECT_EQ(vision::payload_bytes(pfnc::kMono12Packed, 736, 571), 736u * 571u * 3u / 2u);
  const cv::Mat image =
      vision::gige_payload_to_image(wire.data(), wire.size(), 3, 1, pfnc::kMono12Packed);
  ASSERT_EQ(image.type(), CV_16UC1);
  EXPECT_EQ(image.at<uint16_t>(0, 0), 0x123);
  EXPECT_EQ(image.at<uint16_t>(0, 1), 0xABC);
  EXPECT_EQ(image.at<uint16_t>(0, 2), 0xFFF);
  // The stream runs across rows: a 3 x 2 frame's second row starts mid-group.
  const std::vector<uint8_t> two_rows = {0x00, 0x10, 0x00, 0x80, 0x0F, 0xFF, 0x12, 0xC3, 0xAB};
  const cv::Mat rows =
      vision::gige_payload_to_image(two_rows.data(), two_rows.size(), 3, 2, pfnc::kMono12Packed);
  EXPECT_EQ(rows.at<uint16_t>(0, 0), 0x000);
  EXPECT_EQ(rows.at<uint16_t>(0, 1), 0x001);
  EXPECT_EQ(rows.at<uint16_t>(0, 2), 0x80F);
  EXPECT_EQ(rows.at<uint16_t>(1, 0), 0xFF0);
  EXPECT_EQ(rows.at<uint16_t>(1, 1), 0x123);
  EXPECT_EQ(rows.at<uint16_t>(1, 2), 0xABC);
}

// An RGGB mosaic of a uniform colour R = 200, G = 100, B = 40: bilinear
// demosaicing restores each channel exactly away from the border, and the
// luminance is 0.299 R + 0.587 G + 0.114 B = 123.06 (BT.601): 123 after
// rounding, also with OpenCV's fixed-point weights (4899, 9617, 1868) / 2^14.
// Had the mosaic's phase been read as BGGR, R and B would swap:
// 0.299 * 40 + 58.7 + 0.114 * 200 = 93.5.
TEST(GigePixelFormat, BayerRG8IsDemosaicedToLuminance) {
  const int w = 8, h = 6;
  std::vector<uint8_t> wire(static_cast<size_t>(w * h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      wire[static_cast<size_t>(y * w + x)] =
          y % 2 == 0 ? (x % 2 == 0 ? 200 : 100) : (x % 2 == 0 ? 100 : 40);
  const cv::Mat image =
      vision::gige_payload_to_image(wire.data(), wire.size(), w, h, pfnc::kBayerRG8);
  ASSERT_EQ(image.type(), CV_8UC1);
  ASSERT_EQ(image.size(), cv::Size(w, h));
  for (int y = 1; y < h - 1; ++y)
    for (int x = 1; x < w - 1; ++x)
      EXPECT_EQ(image.at<uint8_t>(y, x), 123) << "at " << x << ", " << y;
}

TEST(GigePixelFormat, NamesAndCodesRoundTrip) {
  for (const char* name : {"Mono8", "Mono10", "Mono12", "Mono12Packed", "Mono16", "BayerRG8"})
    EXPECT_EQ(vision::pixel_format_name(vision::pixel_format_code(name)), name);
  EXPECT_EQ(vision::pixel_format_code("Mono12Packed"), 0x010C0006u);
  EXPECT_EQ(vision::pixel_format_name(0x02180014), "0x02180014");  // RGB8: not read
}

TEST(GigePixelFormat, BadBuffersAreErrorsNamingTheFormatAndTheSize) {
  const std::vector<uint8_t> wire(10);
  std::string message = error_of(
      [&] { vision::gige_payload_to_image(wire.data(), wire.size(), 4, 2, pfnc::kMono12Packed); });
  EXPECT_NE(message.find("Mono12Packed frame of 4 x 2: 10 bytes, expected 12"), std::string::npos)
      << message;
  message = error_of([&] { vision::gige_payload_to_image(wire.data(), 10, 2, 1, 0x02180014); });
  EXPECT_NE(message.find("0x02180014"), std::string::npos) << message;
  EXPECT_NE(message.find("Mono12Packed"), std::string::npos) << message;  // lists the readable
  message = error_of([&] { vision::pixel_format_code("RGB8"); });
  EXPECT_NE(message.find("pixel format \"RGB8\": expected one of Mono8"), std::string::npos)
      << message;
  message =
      error_of([&] { vision::gige_payload_to_image(wire.data(), 10, 1, 1, pfnc::kBayerRG8); });
  EXPECT_NE(message.find("expected at least 2 x 2"), std::string::npos) << message;
}

TEST(V4l2PixelFormat, GreyRowsAreCopiedPastTheDriversPadding) {
  // 3 x 2 pixels in rows of 4 bytes: the fourth byte of each row is padding.
  const std::vector<uint8_t> buffer = {10, 20, 30, 99, 40, 50, 60, 99};
  const cv::Mat image =
      vision::v4l2_buffer_to_image(buffer.data(), buffer.size(), 3, 2, 4, fourcc::kGrey);
  ASSERT_EQ(image.type(), CV_8UC1);
  EXPECT_EQ(cv::countNonZero(image != (cv::Mat_<uint8_t>(2, 3) << 10, 20, 30, 40, 50, 60)), 0);
}

TEST(V4l2PixelFormat, YuyvKeepsItsLumaSamples) {
  // Y0 U Y1 V Y2 U Y3 V: luma 16, 235, 100, 101; chroma 128 / 7 / 250 ignored.
  const std::vector<uint8_t> buffer = {16, 128, 235, 7, 100, 250, 101, 128};
  const cv::Mat image =
      vision::v4l2_buffer_to_image(buffer.data(), buffer.size(), 4, 1, 0, fourcc::kYuyv);
  ASSERT_EQ(image.type(), CV_8UC1);
  EXPECT_EQ(cv::countNonZero(image != (cv::Mat_<uint8_t>(1, 4) << 16, 235, 100, 101)), 0);
}

TEST(V4l2PixelFormat, Y16IsKept) {
  const std::vector<uint8_t> buffer = {0x34, 0x12, 0xFF, 0x0F};
  const cv::Mat image =
      vision::v4l2_buffer_to_image(buffer.data(), buffer.size(), 2, 1, 0, fourcc::kY16);
  EXPECT_EQ(image.at<uint16_t>(0, 0), 0x1234);
  EXPECT_EQ(image.at<uint16_t>(0, 1), 0x0FFF);
}

// The root mean square of the error of an IJG quality-95 JPEG is bounded by
// its quantization: the encoder's tables are the standard luminance table
// (ITU-T T.81 Annex K) scaled by (200 - 2 * 95) % = 10 %, each DCT
// coefficient is rounded to a multiple of its step q (error <= q / 2), and
// the 8 x 8 DCT is orthonormal, so a block's pixel MSE is the mean of its 64
// coefficient errors squared: RMS <= sqrt(mean(q^2)) / 2. Rounding the
// decoded pixels to integers and libjpeg's integer IDCT add at most 1 DN.
double jpeg_rms_bound(int quality) {
  static const int annex_k[64] = {16,  11,  10,  16,  24, 40, 51,  61,  12,  12,  14,  19,  26,
                                  58,  60,  55,  14,  13, 16, 24,  40,  57,  69,  56,  14,  17,
                                  22,  29,  51,  87,  80, 62, 18,  22,  37,  56,  68,  109, 103,
                                  77,  24,  35,  55,  64, 81, 104, 113, 92,  49,  64,  78,  87,
                                  103, 121, 120, 101, 72, 92, 95,  98,  112, 100, 103, 99};
  const int scale = quality < 50 ? 5000 / quality : 200 - 2 * quality;
  double sum = 0;
  for (int q : annex_k) {
    const double step = std::max(1, (q * scale + 50) / 100);
    sum += step * step;
  }
  return std::sqrt(sum / 64) / 2 + 1;
}

TEST(V4l2PixelFormat, MjpegDecodesWithinItsQuantizationError) {
  // A pattern with edges and gradients: a ramp, a dark square and a bright bar.
  cv::Mat pattern(48, 64, CV_8UC1);
  for (int y = 0; y < pattern.rows; ++y)
    for (int x = 0; x < pattern.cols; ++x)
      pattern.at<uint8_t>(y, x) = static_cast<uint8_t>(40 + 2 * x + y);
  cv::rectangle(pattern, cv::Rect(8, 8, 16, 16), cv::Scalar(10), cv::FILLED);
  cv::rectangle(pattern, cv::Rect(40, 4, 6, 40), cv::Scalar(240), cv::FILLED);
  std::vector<uint8_t> jpeg;
  ASSERT_TRUE(vision::imencode(".jpg", pattern, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95}));
  const cv::Mat image =
      vision::v4l2_buffer_to_image(jpeg.data(), jpeg.size(), 64, 48, 0, fourcc::kMjpeg);
  ASSERT_EQ(image.type(), CV_8UC1);
  ASSERT_EQ(image.size(), pattern.size());
  const double rms = cv::norm(image, pattern, cv::NORM_L2) / std::sqrt(pattern.total());
  const double bound = jpeg_rms_bound(95);
  EXPECT_LE(rms, bound);
  EXPECT_GT(rms, 0);  // it was compressed: the test cannot pass on a raw copy
  RecordProperty("jpeg_q95_rms_dn", std::to_string(rms));
  RecordProperty("jpeg_q95_rms_bound_dn", std::to_string(bound));
}

TEST(V4l2PixelFormat, BadBuffersAreErrorsNamingTheFourcc) {
  const std::vector<uint8_t> buffer(5, 0);
  std::string message = error_of(
      [&] { vision::v4l2_buffer_to_image(buffer.data(), buffer.size(), 3, 2, 0, fourcc::kGrey); });
  EXPECT_NE(message.find("V4L2 GREY frame of 3 x 2: 5 bytes"), std::string::npos) << message;
  message = error_of(
      [&] { vision::v4l2_buffer_to_image(buffer.data(), buffer.size(), 3, 2, 0, fourcc::kMjpeg); });
  EXPECT_NE(message.find("does not decode as a JPEG"), std::string::npos) << message;
  message = error_of([&] {
    vision::v4l2_buffer_to_image(buffer.data(), buffer.size(), 1, 1, 0,
                                 fourcc::make('N', 'V', '1', '2'));
  });
  EXPECT_NE(message.find("NV12"), std::string::npos) << message;
  cv::Mat small(4, 4, CV_8UC1, cv::Scalar(128));
  std::vector<uint8_t> jpeg;
  vision::imencode(".jpg", small, jpeg);
  message = error_of(
      [&] { vision::v4l2_buffer_to_image(jpeg.data(), jpeg.size(), 8, 8, 0, fourcc::kMjpeg); });
  EXPECT_NE(message.find("JPEG declares 4 x 4 pixels"), std::string::npos) << message;
}

}  // namespace
