// vision::Codebook: pinned ids, the distance property, decoding with rotation
// and bit errors.
#include "vision/codebook.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

namespace vision {
namespace {

// The ids are a public contract (printed targets carry them): the first codes
// of the default book must never change.
TEST(Codebook, DefaultBookPinsItsFirstIdsAndBits) {
  const Codebook book;
  ASSERT_EQ(book.options().min_hamming_distance, 5);
  ASSERT_EQ(book.size(), 35u);
  const std::vector<uint16_t> first = {0x0007, 0x0039, 0x00D2, 0x017E, 0x01E1, 0x02AE};
  for (size_t id = 0; id < first.size(); ++id) {
    EXPECT_EQ(book.code(static_cast<int>(id)), first[id]) << "id " << id;
  }
}

TEST(Codebook, DefaultBookHasAtLeastThirtyIdsWithOneBitCorrection) {
  const Codebook book;
  EXPECT_GE(book.size(), 30u);
  EXPECT_EQ(book.correctable_bits(), 2);
  EXPECT_EQ(book.max_correction_bits(), 1);
}

// The documented trade-off table of the header.
TEST(Codebook, SizeFallsWithTheMinimumDistanceAsDocumented) {
  const std::vector<std::pair<int, size_t>> expected = {{3, 513}, {4, 282}, {6, 23}, {7, 5}};
  for (const auto& [d, n] : expected) {
    EXPECT_EQ(Codebook(CodebookOptions{d, -1}).size(), n) << "d = " << d;
  }
}

// The distance counts the differing bits of every pair: checked against a
// bit-by-bit count for each of the 65,536 differences (a ^ b), from both
// sides of a pair and against a second operand that is not zero.
TEST(Codebook, HammingDistanceCountsTheDifferingBitsOfEveryPair) {
  for (unsigned diff = 0; diff <= 0xFFFF; ++diff) {
    int bits = 0;
    for (int k = 0; k < 16; ++k)
      bits += (diff >> k) & 1;
    const auto a = static_cast<uint16_t>(0xA5C3u ^ diff);
    ASSERT_EQ(Codebook::hamming_distance(static_cast<uint16_t>(diff), 0), bits) << diff;
    ASSERT_EQ(Codebook::hamming_distance(a, 0xA5C3u), bits) << diff;
    ASSERT_EQ(Codebook::hamming_distance(0xA5C3u, a), bits) << diff;
  }
}

TEST(Codebook, EveryRotatedCodeIsAtLeastTheMinimumDistanceFromEveryOther) {
  for (int d : {3, 5}) {
    const Codebook book(CodebookOptions{d, -1});
    std::vector<uint16_t> all;
    for (size_t id = 0; id < book.size(); ++id) {
      for (int r = 0; r < 4; ++r) {
        all.push_back(Codebook::rotate_clockwise(book.code(static_cast<int>(id)), r));
      }
    }
    int min_distance = 16;
    for (size_t i = 0; i < all.size(); ++i) {
      for (size_t j = i + 1; j < all.size(); ++j) {
        min_distance = std::min(min_distance, Codebook::hamming_distance(all[i], all[j]));
      }
    }
    // Includes each code against its own rotations: no code is rotation-symmetric.
    EXPECT_GE(min_distance, d);
  }
}

TEST(Codebook, RotationTurnsTheTopLeftCellToTheTopRight) {
  const uint16_t top_left = 1u << 15;
  EXPECT_EQ(Codebook::rotate_clockwise(top_left, 1), 1u << 12);
  EXPECT_EQ(Codebook::rotate_clockwise(top_left, 2), 1u << 0);
  EXPECT_EQ(Codebook::rotate_clockwise(top_left, 3), 1u << 3);
  EXPECT_EQ(Codebook::rotate_clockwise(top_left, -1), 1u << 3);
  EXPECT_EQ(Codebook::rotate_clockwise(0xBEEF, 4), 0xBEEF);
}

TEST(Codebook, MarkerGridHasABlackBorderAroundTheCode) {
  const uint16_t all_white = 0xFFFF;
  for (int i = 0; i < kMarkerCells; ++i) {
    EXPECT_FALSE(Codebook::marker_cell_is_white(all_white, 0, i));
    EXPECT_FALSE(Codebook::marker_cell_is_white(all_white, 5, i));
    EXPECT_FALSE(Codebook::marker_cell_is_white(all_white, i, 0));
    EXPECT_FALSE(Codebook::marker_cell_is_white(all_white, i, 5));
  }
  EXPECT_TRUE(Codebook::marker_cell_is_white(uint16_t{1u << 15}, 1, 1));
  EXPECT_FALSE(Codebook::marker_cell_is_white(uint16_t{1u << 15}, 1, 2));
}

TEST(Codebook, DecodesEveryIdInEveryRotation) {
  const Codebook book;
  for (size_t id = 0; id < book.size(); ++id) {
    for (int r = 0; r < 4; ++r) {
      const auto result =
          book.decode(Codebook::rotate_clockwise(book.code(static_cast<int>(id)), r));
      ASSERT_TRUE(result.has_value());
      EXPECT_EQ(result->id, static_cast<int>(id));
      EXPECT_EQ(result->rotation, r);
      EXPECT_EQ(result->bits_corrected, 0);
    }
  }
}

TEST(Codebook, CorrectsOneFlippedCellInEveryPositionAndRotation) {
  const Codebook book;
  for (size_t id = 0; id < book.size(); ++id) {
    for (int r = 0; r < 4; ++r) {
      const uint16_t seen = Codebook::rotate_clockwise(book.code(static_cast<int>(id)), r);
      for (int bit = 0; bit < 16; ++bit) {
        const auto result = book.decode(static_cast<uint16_t>(seen ^ (1u << bit)));
        ASSERT_TRUE(result.has_value()) << "id " << id << " rot " << r << " bit " << bit;
        EXPECT_EQ(result->id, static_cast<int>(id));
        EXPECT_EQ(result->rotation, r);
        EXPECT_EQ(result->bits_corrected, 1);
      }
    }
  }
}

// With d = 5 a 2-bit error is still closer to the true code than to any other
// (distance 2 vs >= 3): rejected by default, corrected when allowed.
TEST(Codebook, RejectsTwoFlippedCellsByDefaultAndCorrectsThemWhenAllowed) {
  const Codebook strict;
  const Codebook lenient(CodebookOptions{5, 2});
  std::mt19937 rng(7);
  for (int trial = 0; trial < 500; ++trial) {
    const int id = static_cast<int>(rng() % strict.size());
    const int r = static_cast<int>(rng() % 4);
    const int b1 = static_cast<int>(rng() % 16);
    int b2 = static_cast<int>(rng() % 15);
    if (b2 >= b1) ++b2;
    const auto seen = static_cast<uint16_t>(Codebook::rotate_clockwise(strict.code(id), r) ^
                                            (1u << b1) ^ (1u << b2));
    EXPECT_FALSE(strict.decode(seen).has_value());
    const auto result = lenient.decode(seen);
    ASSERT_TRUE(result.has_value());
    EXPECT_EQ(result->id, id);
    EXPECT_EQ(result->rotation, r);
    EXPECT_EQ(result->bits_corrected, 2);
  }
}

// The header's false-acceptance figure: 4 * 35 * (1 + 16) / 65536 = 3.63 % of
// all patterns decode with 1-bit correction (exact: the balls are disjoint).
TEST(Codebook, AcceptsTheDocumentedFractionOfRandomPatterns) {
  const Codebook book;
  int accepted = 0;
  for (uint32_t bits = 0; bits <= 0xFFFFu; ++bits) {
    accepted += book.decode(static_cast<uint16_t>(bits)).has_value() ? 1 : 0;
  }
  EXPECT_EQ(accepted, 4 * 35 * 17);
}

TEST(Codebook, RejectsOutOfRangeIdsAndOptions) {
  const Codebook book;
  EXPECT_THROW(book.code(-1), std::out_of_range);
  EXPECT_THROW(book.code(static_cast<int>(book.size())), std::out_of_range);
  EXPECT_THROW(Codebook(CodebookOptions{0, 1}), std::invalid_argument);
  EXPECT_THROW(Codebook(CodebookOptions{17, 1}), std::invalid_argument);
}

}  // namespace
}  // namespace vision
