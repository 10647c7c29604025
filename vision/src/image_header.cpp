// The header of an image file, read byte by byte with every offset checked
// against the data's size. Layouts: PNG (ISO/IEC 15948, IHDR), JPEG (ITU-T
// T.81 B.2.2, frame header), TIFF 6.0 (section 2, the first IFD), Netpbm
// (pbm/pgm/ppm/pam) and BMP (BITMAPCOREHEADER / BITMAPINFOHEADER).
#include <algorithm>
#include <cctype>
#include <cstdlib>

#include "vision/detector_image.hpp"

namespace vision {
namespace {

// The bytes of a file or a buffer, not owned.
struct Bytes {
  const std::uint8_t* data;
  std::size_t length;
  std::size_t size() const { return length; }
  std::uint8_t operator[](std::size_t i) const { return data[i]; }
  const std::uint8_t* begin() const { return data; }
};

// Unsigned integer of `n` bytes at `at`, big- or little-endian; false when
// the data ends first.
bool read_uint(const Bytes& b, std::size_t at, int n, bool big_endian, std::uint32_t* value) {
  if (at > b.size() || b.size() - at < static_cast<std::size_t>(n)) return false;
  std::uint32_t v = 0;
  for (int i = 0; i < n; ++i) {
    const std::uint32_t byte = b[at + (big_endian ? i : n - 1 - i)];
    v = (v << 8) | byte;
  }
  *value = v;
  return true;
}

bool starts_with(const Bytes& b, std::initializer_list<std::uint8_t> magic) {
  return b.size() >= magic.size() && std::equal(magic.begin(), magic.end(), b.begin());
}

[[noreturn]] void refuse(const std::string& name, const std::string& format,
                         const std::string& what) {
  throw ImageError(name + ": " + format + " header " + what);
}

ImageHeader png_header(const Bytes& b, const std::string& name) {
  static const std::uint8_t ihdr[] = {0, 0, 0, 13, 'I', 'H', 'D', 'R'};
  if (b.size() < 8 + 8 + 13 || !std::equal(std::begin(ihdr), std::end(ihdr), b.begin() + 8))
    refuse(name, "PNG", "does not start with a 13-byte IHDR chunk");
  ImageHeader h{"PNG"};
  std::uint32_t w = 0, ht = 0;
  read_uint(b, 16, 4, true, &w);
  read_uint(b, 20, 4, true, &ht);
  h.width = w;
  h.height = ht;
  const int depth = b[24], colour = b[25];
  // Colour types 0 grey, 2 RGB, 3 palette (decoded as BGR or BGRA), 4 grey +
  // alpha, 6 RGBA.
  static const int channels[] = {1, 0, 3, 4, 2, 0, 4};
  if (colour > 6 || channels[colour] == 0)
    refuse(name, "PNG", "has colour type " + std::to_string(colour) + "; expected 0, 2, 3, 4 or 6");
  if (depth != 1 && depth != 2 && depth != 4 && depth != 8 && depth != 16)
    refuse(name, "PNG", "has bit depth " + std::to_string(depth) + "; expected 1, 2, 4, 8 or 16");
  h.channels = channels[colour];
  h.bytes_per_sample = depth == 16 ? 2 : 1;
  return h;
}

// The first start-of-frame marker (SOF0-SOF15 but DHT C4, JPG C8, DAC CC),
// walking the marker segments from SOI.
ImageHeader jpeg_header(const Bytes& b, const std::string& name) {
  std::size_t at = 2;
  while (true) {
    while (at < b.size() && b[at] == 0xFF && at + 1 < b.size() && b[at + 1] == 0xFF)
      ++at;
    std::uint32_t marker = 0, length = 0;
    if (!read_uint(b, at, 2, true, &marker) || (marker >> 8) != 0xFF)
      refuse(name, "JPEG", "ends or breaks off before its frame header (SOF marker)");
    const std::uint32_t code = marker & 0xFF;
    if (code == 0xD9 || code == 0xDA)
      refuse(name, "JPEG", "reaches its scan before a frame header (SOF marker)");
    if ((code >= 0xD0 && code <= 0xD8) || code == 0x01) {  // markers without a length
      at += 2;
      continue;
    }
    if (!read_uint(b, at + 2, 2, true, &length) || length < 2)
      refuse(name, "JPEG", "has a marker segment cut short");
    const bool sof = code >= 0xC0 && code <= 0xCF && code != 0xC4 && code != 0xC8 && code != 0xCC;
    if (sof) {
      std::uint32_t precision = 0, ht = 0, w = 0, components = 0;
      if (length < 8 || !read_uint(b, at + 4, 1, true, &precision) ||
          !read_uint(b, at + 5, 2, true, &ht) || !read_uint(b, at + 7, 2, true, &w) ||
          !read_uint(b, at + 9, 1, true, &components))
        refuse(name, "JPEG", "has a frame header cut short");
      if (components < 1 || components > 4)
        refuse(name, "JPEG",
               "declares " + std::to_string(components) + " components; expected 1 to 4");
      ImageHeader h{"JPEG"};
      h.width = w;
      h.height = ht;
      h.channels = static_cast<int>(components);
      h.bytes_per_sample = precision > 8 ? 2 : 1;
      return h;
    }
    at += 2 + length;
  }
}

// TIFF: the first IFD's ImageWidth (256), ImageLength (257), BitsPerSample
// (258, the first value) and SamplesPerPixel (277, default 1).
ImageHeader tiff_header(const Bytes& b, const std::string& name) {
  const bool big = b[0] == 'M';
  std::uint32_t ifd = 0, count = 0;
  if (!read_uint(b, 4, 4, big, &ifd) || !read_uint(b, ifd, 2, big, &count))
    refuse(name, "TIFF", "points to a first IFD beyond the end of the data");
  ImageHeader h{"TIFF"};
  h.channels = 1;
  h.bytes_per_sample = 1;
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::size_t entry = ifd + 2 + 12 * static_cast<std::size_t>(i);
    std::uint32_t tag = 0, type = 0, values = 0, value = 0;
    if (!read_uint(b, entry, 2, big, &tag) || !read_uint(b, entry + 2, 2, big, &type) ||
        !read_uint(b, entry + 4, 4, big, &values))
      refuse(name, "TIFF", "has an IFD cut short");
    const bool wanted = tag == 256 || tag == 257 || tag == 258 || tag == 277;
    if (!wanted || (type != 3 && type != 4)) continue;  // SHORT or LONG
    const int size = type == 3 ? 2 : 4;
    // The first value: left-justified in the value field when all fit in its
    // 4 bytes, else at the offset the field holds.
    std::size_t at = entry + 8;
    if (values * static_cast<std::uint64_t>(size) > 4) {
      std::uint32_t offset = 0;
      read_uint(b, entry + 8, 4, big, &offset);
      at = offset;
    }
    if (!read_uint(b, at, size, big, &value)) refuse(name, "TIFF", "has a tag value cut short");
    if (tag == 256) h.width = value;
    if (tag == 257) h.height = value;
    if (tag == 258) h.bytes_per_sample = value > 8 ? 2 : 1;
    if (tag == 277) h.channels = static_cast<int>(std::min<std::uint32_t>(value, 5));
  }
  if (h.channels < 1 || h.channels > 4)
    refuse(name, "TIFF",
           "declares " + std::string(h.channels < 1 ? "0" : "more than 4") +
               " samples per pixel; expected 1 to 4");
  return h;
}

// Netpbm: "P1".."P6" then width, height (and maxval) as decimal numbers
// separated by white space and '#' comments; "P7" (PAM) as WIDTH, HEIGHT,
// DEPTH and MAXVAL lines up to ENDHDR.
class PnmTokens {
 public:
  explicit PnmTokens(const Bytes& b) : b_(b) {}
  // The next token, at most 32 characters; empty when the data ends.
  std::string next() {
    while (pos_ < b_.size()) {
      if (b_[pos_] == '#') {
        while (pos_ < b_.size() && b_[pos_] != '\n')
          ++pos_;
      } else if (std::isspace(b_[pos_])) {
        ++pos_;
      } else {
        break;
      }
    }
    std::string token;
    while (pos_ < b_.size() && !std::isspace(b_[pos_]) && b_[pos_] != '#' && token.size() < 32)
      token += static_cast<char>(b_[pos_++]);
    return token;
  }

 private:
  const Bytes& b_;
  std::size_t pos_ = 2;
};

std::int64_t pnm_number(const std::string& token, const char* what, const std::string& name) {
  if (token.empty() || token.size() > 10 ||
      !std::all_of(token.begin(), token.end(), [](char c) { return c >= '0' && c <= '9'; }))
    refuse(name, "PNM", std::string("has ") + what + " '" + token + "'; expected a whole number");
  return std::strtoll(token.c_str(), nullptr, 10);
}

ImageHeader pnm_header(const Bytes& b, const std::string& name) {
  ImageHeader h{"PNM"};
  PnmTokens tokens(b);
  const char kind = static_cast<char>(b[1]);
  std::int64_t maxval = 1;
  if (kind == '7') {
    h.channels = 1;
    for (std::string key = tokens.next(); key != "ENDHDR"; key = tokens.next()) {
      if (key.empty()) refuse(name, "PAM", "ends before ENDHDR");
      if (key == "WIDTH") h.width = pnm_number(tokens.next(), "WIDTH", name);
      if (key == "HEIGHT") h.height = pnm_number(tokens.next(), "HEIGHT", name);
      if (key == "DEPTH")
        h.channels =
            static_cast<int>(std::min<std::int64_t>(pnm_number(tokens.next(), "DEPTH", name), 5));
      if (key == "MAXVAL") maxval = pnm_number(tokens.next(), "MAXVAL", name);
    }
    if (h.channels < 1 || h.channels > 4) refuse(name, "PAM", "has a DEPTH other than 1 to 4");
  } else {
    h.width = pnm_number(tokens.next(), "a width", name);
    h.height = pnm_number(tokens.next(), "a height", name);
    if (kind != '1' && kind != '4') maxval = pnm_number(tokens.next(), "a maximum value", name);
    h.channels = kind == '3' || kind == '6' ? 3 : 1;
  }
  h.bytes_per_sample = maxval > 255 ? 2 : 1;
  return h;
}

// BMP: the info header's width and height (negative height: rows top-down),
// decoded as at most 4 channels of 8 bits.
ImageHeader bmp_header(const Bytes& b, const std::string& name) {
  std::uint32_t info_size = 0, w = 0, ht = 0;
  if (!read_uint(b, 14, 4, false, &info_size)) refuse(name, "BMP", "ends before its info header");
  const bool core = info_size == 12;  // BITMAPCOREHEADER: 16-bit dimensions
  if (!read_uint(b, 18, core ? 2 : 4, false, &w) ||
      !read_uint(b, core ? 20 : 22, core ? 2 : 4, false, &ht))
    refuse(name, "BMP", "ends before its width and height");
  ImageHeader h{"BMP"};
  h.width = core ? std::int64_t{w} : std::int64_t{static_cast<std::int32_t>(w)};
  const std::int64_t height = core ? std::int64_t{ht} : std::int64_t{static_cast<std::int32_t>(ht)};
  h.height = height < 0 ? -height : height;
  h.channels = 4;
  h.bytes_per_sample = 1;
  return h;
}

}  // namespace

ImageHeader read_image_header(const std::uint8_t* data, std::size_t size, const std::string& name) {
  const Bytes bytes{data, data == nullptr ? 0 : size};
  ImageHeader h;
  if (starts_with(bytes, {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A})) {
    h = png_header(bytes, name);
  } else if (starts_with(bytes, {0xFF, 0xD8})) {
    h = jpeg_header(bytes, name);
  } else if (starts_with(bytes, {'I', 'I', 42, 0}) || starts_with(bytes, {'M', 'M', 0, 42})) {
    h = tiff_header(bytes, name);
  } else if (bytes.size() >= 2 && bytes[0] == 'P' && bytes[1] >= '1' && bytes[1] <= '7') {
    h = pnm_header(bytes, name);
  } else if (starts_with(bytes, {'B', 'M'})) {
    h = bmp_header(bytes, name);
  } else {
    throw ImageError(name + ": is not an image rig reads (expected PNG, JPEG, TIFF, " +
                     "PGM/PPM or BMP)");
  }
  if (h.width < 1 || h.height < 1)
    refuse(name, h.format,
           "declares " + std::to_string(h.width) + " x " + std::to_string(h.height) +
               " pixels; expected at least 1 x 1");
  // Each side first, so that the products below cannot overflow.
  if (h.width > kMaxImagePixels || h.height > kMaxImagePixels ||
      h.width * h.height > kMaxImagePixels || h.decoded_bytes() > kMaxImageBytes)
    refuse(name, h.format,
           "declares " + std::to_string(h.width) + " x " + std::to_string(h.height) +
               " pixels; expected at most " + std::to_string(kMaxImagePixels / 1000000) +
               " Mpx and " + std::to_string(kMaxImageBytes >> 30) + " GiB decoded");
  return h;
}

}  // namespace vision
