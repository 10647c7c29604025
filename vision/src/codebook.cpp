// Codebook construction and decoding (see vision/codebook.hpp).
#include "vision/codebook.hpp"

#include <array>
#include <stdexcept>
#include <string>

namespace vision {

namespace {

// One clockwise quarter turn: cell (r, c) moves to (c, 3 - r).
uint16_t rotate_once(uint16_t bits) {
  uint16_t out = 0;
  for (int r = 0; r < kCodeCells; ++r) {
    for (int c = 0; c < kCodeCells; ++c) {
      if (Codebook::cell_is_white(bits, r, c)) {
        out = static_cast<uint16_t>(out | (1u << Codebook::bit_index(c, kCodeCells - 1 - r)));
      }
    }
  }
  return out;
}

}  // namespace

Codebook::Codebook(Options options) : options_(options) {
  const int d = options_.min_hamming_distance;
  if (d < 1 || d > 16) {
    throw std::invalid_argument("Codebook: min_hamming_distance = " + std::to_string(d) +
                                ", expected 1 .. 16");
  }
  if (options_.max_correction_bits < -1) {
    throw std::invalid_argument(
        "Codebook: max_correction_bits = " + std::to_string(options_.max_correction_bits) +
        ", expected -1 (all correctable) or >= 0");
  }
  std::vector<uint16_t> accepted_rotations;
  for (uint32_t candidate = 0; candidate <= 0xFFFFu; ++candidate) {
    const auto c = static_cast<uint16_t>(candidate);
    std::array<uint16_t, 4> rotations{c, 0, 0, 0};
    bool ok = true;
    for (int k = 1; k < 4 && ok; ++k) {
      rotations[k] = rotate_once(rotations[k - 1]);
      ok = hamming_distance(c, rotations[k]) >= d;
    }
    for (size_t i = 0; i < accepted_rotations.size() && ok; ++i) {
      ok = hamming_distance(c, accepted_rotations[i]) >= d;
    }
    if (!ok) continue;
    codes_.push_back(c);
    accepted_rotations.insert(accepted_rotations.end(), rotations.begin(), rotations.end());
  }
}

uint16_t Codebook::code(int id) const {
  if (id < 0 || static_cast<size_t>(id) >= codes_.size()) {
    throw std::out_of_range("Codebook: id " + std::to_string(id) + " not in 0 .. " +
                            std::to_string(static_cast<int>(codes_.size()) - 1));
  }
  return codes_[static_cast<size_t>(id)];
}

int Codebook::max_correction_bits() const {
  const int limit = correctable_bits();
  if (options_.max_correction_bits < 0) return limit;
  return options_.max_correction_bits < limit ? options_.max_correction_bits : limit;
}

std::optional<DecodeResult> Codebook::decode(uint16_t observed_bits) const {
  // Undo the observed rotation instead of storing rotated codes: observed =
  // rotate(code, r)  <=>  rotate(observed, -r) = code.
  std::array<uint16_t, 4> unrotated{observed_bits, 0, 0, 0};
  for (int r = 1; r < 4; ++r)
    unrotated[r] = rotate_clockwise(observed_bits, -r);
  const int max_bits = max_correction_bits();
  for (size_t id = 0; id < codes_.size(); ++id) {
    for (int r = 0; r < 4; ++r) {
      const int distance = hamming_distance(unrotated[r], codes_[id]);
      // Within the correction radius the nearest code is unique, so the first
      // hit is the answer.
      if (distance <= max_bits) return DecodeResult{static_cast<int>(id), r, distance};
    }
  }
  return std::nullopt;
}

uint16_t Codebook::rotate_clockwise(uint16_t bits, int quarter_turns) {
  const int turns = ((quarter_turns % 4) + 4) % 4;
  for (int k = 0; k < turns; ++k)
    bits = rotate_once(bits);
  return bits;
}

bool Codebook::marker_cell_is_white(uint16_t bits, int row, int col) {
  if (row <= 0 || col <= 0 || row >= kMarkerCells - 1 || col >= kMarkerCells - 1) return false;
  return cell_is_white(bits, row - 1, col - 1);
}

int Codebook::hamming_distance(uint16_t a, uint16_t b) {
  // The bits set in a ^ b, counted in parallel (pairs, nibbles, bytes): a
  // few integer operations inline, where std::bitset::count is a libgcc call
  // on x86-64 builds without POPCNT, and decode() makes up to 4 * size() of
  // them a candidate.
  unsigned x = static_cast<unsigned>(a ^ b);
  x -= (x >> 1) & 0x5555u;
  x = (x & 0x3333u) + ((x >> 2) & 0x3333u);
  x = (x + (x >> 4)) & 0x0F0Fu;
  return static_cast<int>((x + (x >> 8)) & 0x1Fu);
}

}  // namespace vision
