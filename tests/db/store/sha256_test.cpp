// SHA-256 against the FIPS 180-2 appendix B examples (and the usual empty
// string and padding-boundary values), fed whole and in odd-sized pieces so that block boundaries
// fall everywhere.
#include "db/store/sha256.hpp"

#include <gtest/gtest.h>

#include <string>
#include <utility>

namespace {

TEST(Sha256, MatchesFips180_2OneBlockMessage) {
  EXPECT_EQ(db::store::sha256_hex("abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(Sha256, MatchesFips180_2MultiBlockMessage) {
  EXPECT_EQ(db::store::sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST(Sha256, MatchesFips180_2MillionAs) {
  EXPECT_EQ(db::store::sha256_hex(std::string(1'000'000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Sha256, HashesTheEmptyMessage) {
  EXPECT_EQ(db::store::sha256_hex(""),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

// The padding edge cases: 55 bytes leave room for the 0x80 byte and the
// 8-byte length in one block, 56 do not; 64 fills a block exactly. Expected
// values from coreutils' sha256sum.
TEST(Sha256, PadsMessagesAtTheBlockBoundaries) {
  const std::pair<std::size_t, const char*> cases[] = {
      {55, "9f4390f8d30c2dd92ec9f095b65e2b9ae9b0a925a5258e241c9f1e910f734318"},
      {56, "b35439a4ac6f0948b6d6f9e3c6af0f5f590ce20f1bde7090ef7970686ec6738a"},
      {63, "7d3e74a05d7db15bce4ad9ec0658ea98e3f06eeecf16b4c6fff2da457ddc2f34"},
      {64, "ffe054fe7ae0cb6dc65c3af9b61d5209f439851db43d0ba5997337df154668eb"},
      {65, "635361c48bb9eab14198e76ea8ab7f1a41685d6ad62aa9146d301d4f17eb0ae0"},
  };
  for (const auto& [length, expected] : cases) {
    EXPECT_EQ(db::store::sha256_hex(std::string(length, 'a')), expected) << "length " << length;
  }
}

TEST(Sha256, GivesTheSameDigestWhateverTheUpdateSizes) {
  // 55, 56 and 64 bytes are the padding edge cases (length fits / does not
  // fit in the last block); pieces of 1..13 bytes cross every boundary.
  for (std::size_t length : {55u, 56u, 63u, 64u, 65u, 200u}) {
    std::string message;
    for (std::size_t i = 0; i < length; ++i)
      message.push_back(static_cast<char>(i * 37));
    db::store::Sha256 pieces;
    std::size_t at = 0;
    for (std::size_t piece = 1; at < length; piece = piece % 13 + 1) {
      const std::size_t take = std::min(piece, length - at);
      pieces.update(message.data() + at, take);
      at += take;
    }
    EXPECT_EQ(pieces.hex_digest(), db::store::sha256_hex(message)) << "length " << length;
  }
}

}  // namespace
