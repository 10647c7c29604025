// vision::Codebook: the 16-bit codes inside the paper's square fiducials.
//
// A marker of side s is a 6x6 grid of equal cells (cell = s / 6): a one-cell
// black border around a 4x4 code grid (Maidi et al. 2010, §3, Figs. 6-7).
//
// Bit layout of a code (uint16_t): bit 15 is the top-left code cell, row-major
// (bit 14 is the cell to its right, ..., bit 12 the top-right, bit 11 the first
// cell of the second row), bit 0 the bottom-right. A bit of 1 is a WHITE cell,
// 0 a black one. Rotation 0 is the marker as printed, seen from the front.
//
// Construction (deterministic, ids stable across versions): the candidates
// 0x0000 .. 0xFFFF are visited in increasing order; a candidate c is accepted
// when
//   - its Hamming distance to each of its own three non-trivial rotations is
//     >= min_hamming_distance (this rejects rotation-symmetric codes, whose
//     orientation would be ambiguous, paper §3 and Fig. 7), and
//   - its Hamming distance to every rotation of every code accepted before it
//     is >= min_hamming_distance.
// The id of a code is its acceptance index. Hence all 4 * size() rotated codes
// are pairwise at least min_hamming_distance apart, and a grid read with up to
// floor((d - 1) / 2) wrong cells decodes uniquely (id and orientation).
//
// Trade-off of min_hamming_distance d (greedy counts, pinned by the tests):
//   d = 3: 513 ids, corrects 1 bit;   d = 4: 282 ids, corrects 1 bit and
//   detects 2;   d = 5: 35 ids, corrects 2;   d = 6: 23 ids;   d = 7: 5 ids.
// Larger d means fewer ids but fewer false identifications: a random 16-bit
// pattern (clutter) is accepted when it lies within the correction radius r of
// one of the 4 * size() rotated codes, with probability
//   4 * size() * sum_{k<=r} C(16, k) / 65536.
// The default d = 5 gives 35 ids (>= 30, the paper's target sheets need 4) and
// by default corrects max_correction_bits = 1 (false acceptance of a random
// pattern 4 * 35 * 17 / 65536 = 3.6 %; 2-bit correction would raise it to
// 29 %, which is AprilTag tag16h5's known weakness) while every 2- or 3-bit
// error is still detected and rejected rather than mis-identified.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace vision {

constexpr int kMarkerCells = 6;  // cells along a marker side, border included
constexpr int kCodeCells = 4;    // code cells along a side (kMarkerCells - 2)

struct DecodeResult {
  int id = -1;  // index into the codebook
  // The observed grid equals code(id) rotated by `rotation` quarter turns
  // clockwise (rotate_clockwise(code(id), rotation)), 0-3.
  int rotation = 0;
  int bits_corrected = 0;  // Hamming distance between observed and that rotated code
};

struct CodebookOptions {
  // Minimum Hamming distance between any two of the 4 * size() rotated codes
  // (see the trade-off above). Must be in [1, 16]; std::invalid_argument otherwise.
  int min_hamming_distance = 5;
  // Largest number of wrong cells decode() corrects. -1 means
  // correctable_bits() = floor((d - 1) / 2). Values above correctable_bits()
  // are clamped to it (beyond, decoding would not be unique). Fewer corrected
  // bits: fewer false identifications of clutter, more rejected real markers
  // whose code cells are misread (blur, glare, occlusion).
  int max_correction_bits = 1;
};

class Codebook {
 public:
  // Declared outside the class so that `Options{}` can be a default argument
  // (GCC rejects a nested aggregate with member initializers there).
  using Options = CodebookOptions;

  explicit Codebook(Options options = {});

  // Number of ids; ids are 0 .. size() - 1.
  size_t size() const { return codes_.size(); }
  // The code of an id at rotation 0. Precondition: 0 <= id < size()
  // (std::out_of_range otherwise).
  uint16_t code(int id) const;
  const std::vector<uint16_t>& codes() const { return codes_; }
  const Options& options() const { return options_; }

  // The nearest rotated code to an observed grid, if its distance is at most
  // max_correction_bits(); std::nullopt otherwise (too many errors, or not a code).
  std::optional<DecodeResult> decode(uint16_t observed_bits) const;

  // The grid turned by quarter_turns * 90 degrees clockwise (as seen printed):
  // the cell at (row r, col c) moves to (row c, col 3 - r). Any integer
  // quarter_turns (taken modulo 4, negatives turn anticlockwise).
  static uint16_t rotate_clockwise(uint16_t bits, int quarter_turns);

  // Bit index (15 .. 0) of the code cell at row, col (0 .. 3, row 0 on top).
  static int bit_index(int row, int col) { return 15 - (row * kCodeCells + col); }
  // Whether the code cell at row, col is white.
  static bool cell_is_white(uint16_t bits, int row, int col) {
    return ((bits >> bit_index(row, col)) & 1u) != 0;
  }
  // Whether cell (row, col) of the full 6x6 marker grid (row 0 on top; border
  // cells included) is white for a given code.
  static bool marker_cell_is_white(uint16_t bits, int row, int col);

  static int hamming_distance(uint16_t a, uint16_t b);

  // floor((min_hamming_distance - 1) / 2): the most errors that can be
  // corrected uniquely.
  int correctable_bits() const { return (options_.min_hamming_distance - 1) / 2; }
  // The correction decode() applies (options().max_correction_bits resolved).
  int max_correction_bits() const;

 private:
  Options options_;
  std::vector<uint16_t> codes_;
};

}  // namespace vision
