#pragma once
// SHA-256 (FIPS 180-4, identical to FIPS 180-2 for this function), for the
// hashes of the files a run stores (sweep file, calibration, layout, geometry,
// bench profile) and of saved raw frames. Our own small implementation because
// no library that provides it is linked (OpenSSL is not a dependency of rig);
// it is tested against the FIPS 180-2 appendix B vectors.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace db::store {

// Incremental hasher: update() any number of times, then digest() or
// hex_digest() once. Never throws.
class Sha256 {
 public:
  Sha256();
  // Appends size bytes at data to the message. Precondition: no digest yet.
  void update(const void* data, std::size_t size);
  void update(std::string_view bytes) { update(bytes.data(), bytes.size()); }
  // The 32-byte digest. Finalises the hasher: call it once, after the last update().
  std::array<std::uint8_t, 32> digest();
  // digest() as 64 lowercase hexadecimal characters (as sha256sum prints it).
  std::string hex_digest();

 private:
  void compress(const std::uint8_t* block);
  std::array<std::uint32_t, 8> state_;
  std::array<std::uint8_t, 64> buffer_{};
  std::size_t buffered_ = 0;
  std::uint64_t total_bytes_ = 0;
};

// SHA-256 of bytes, as 64 lowercase hexadecimal characters.
std::string sha256_hex(std::string_view bytes);

}  // namespace db::store
