// The image halved for the candidate stage: cv::pyrDown's pixels in less time.
//
// cv::pyrDown on 8-bit images is exact integer arithmetic: the separable 5x5
// binomial kernel [1 4 6 4 1]^T [1 4 6 4 1] / 256 on every other row and
// column, BORDER_REFLECT_101, rounded by (sum + 128) >> 8. A sum of integer
// products does not depend on the order of its terms, so filtering the
// columns first and the rows second gives the same pixels. Here, per output
// row, the five input rows are summed column by column, already split into
// even and odd columns (read two pixels at a time as one 16-bit word, whose
// low byte is the even column and high byte the odd one), and the row filter
// then reads both halves contiguously: every loop is a plain element-wise
// loop that the compiler vectorizes, in 16-bit lanes (the largest sum,
// 16 x 16 x 255 + 128 = 65,408, fits). On x86-64 the loops are compiled a
// second time for AVX2 and chosen at run time.
#include <cstdint>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "detector_internal.hpp"

namespace vision::detail {
namespace {

// Index of row or column p of an axis of n pixels under BORDER_REFLECT_101
// (... 2 1 | 0 1 2 ... n-1 | n-2 ...). Precondition: n >= 4 and -2 <= p <= n + 1.
int reflect_101(int p, int n) {
  return p < 0 ? -p : p >= n ? 2 * n - 2 - p : p;
}

// Column sums of the five input rows at the pairs of columns (2j, 2j + 1),
// j < pairs, split into even[j] and odd[j].
inline void sum_column_pairs(const std::uint8_t* __restrict r0, const std::uint8_t* __restrict r1,
                             const std::uint8_t* __restrict r2, const std::uint8_t* __restrict r3,
                             const std::uint8_t* __restrict r4, int pairs,
                             std::uint16_t* __restrict even, std::uint16_t* __restrict odd) {
  for (int j = 0; j < pairs; ++j) {
    // Two pixels as one little-endian word: low byte column 2j, high 2j + 1.
    std::uint16_t q0, q1, q2, q3, q4;
    std::memcpy(&q0, r0 + 2 * j, 2);
    std::memcpy(&q1, r1 + 2 * j, 2);
    std::memcpy(&q2, r2 + 2 * j, 2);
    std::memcpy(&q3, r3 + 2 * j, 2);
    std::memcpy(&q4, r4 + 2 * j, 2);
    even[j] = static_cast<std::uint16_t>((q0 & 0xFF) + (q4 & 0xFF) +
                                         4 * ((q1 & 0xFF) + (q3 & 0xFF)) + 6 * (q2 & 0xFF));
    odd[j] = static_cast<std::uint16_t>((q0 >> 8) + (q4 >> 8) + 4 * ((q1 >> 8) + (q3 >> 8)) +
                                        6 * (q2 >> 8));
  }
}

// The row filter at output columns x < width from the column sums of input
// columns 2x - 2 .. 2x + 2, which are e[x], o[x], e[x + 1], o[x + 1], e[x + 2]
// (e[j] = even[j - 1], o[j] = odd[j - 1]).
inline void filter_row(const std::uint16_t* __restrict e, const std::uint16_t* __restrict o,
                       int width, std::uint8_t* __restrict out) {
  for (int x = 0; x < width; ++x)
    out[x] = static_cast<std::uint8_t>(
        static_cast<std::uint16_t>(e[x] + e[x + 2] + 6 * e[x + 1] + 4 * (o[x] + o[x + 1]) + 128) >>
        8);
}

// Both loops per output row; the column sums of the border columns (outside
// the pairs, reflected) one at a time.
inline void halve_rows(const cv::Mat& gray, cv::Mat* half) {
  const int cols = gray.cols, rows = gray.rows, width = half->cols, pairs = cols / 2;
  // Column sums of columns -2 .. 2 * width, split into even and odd.
  std::vector<std::uint16_t> even_sums(static_cast<std::size_t>(width) + 3),
      odd_sums(static_cast<std::size_t>(width) + 3);
  std::uint16_t* even = even_sums.data() + 1;  // even[-1]: column -2
  std::uint16_t* odd = odd_sums.data() + 1;
  for (int y = 0; y < half->rows; ++y) {
    const std::uint8_t* r[5];
    for (int k = 0; k < 5; ++k)
      r[k] = gray.ptr<std::uint8_t>(reflect_101(2 * y - 2 + k, rows));
    sum_column_pairs(r[0], r[1], r[2], r[3], r[4], pairs, even, odd);
    const auto column = [&r](int c) {
      return static_cast<std::uint16_t>(r[0][c] + r[4][c] + 4 * (r[1][c] + r[3][c]) + 6 * r[2][c]);
    };
    // The filter reads columns -2 .. 2 * width: those outside the pairs
    // reflect (-2, -1 to 2, 1; cols to cols - 2; cols + 1 to cols - 3), and
    // an odd width leaves column cols - 1 outside them.
    even[-1] = column(2);
    odd[-1] = column(1);
    if (cols % 2) {
      even[pairs] = column(cols - 1);
      odd[pairs] = column(cols - 2);
      even[pairs + 1] = column(cols - 3);
    } else {
      even[pairs] = column(cols - 2);
    }
    filter_row(even - 1, odd - 1, width, half->ptr<std::uint8_t>(y));
  }
}

VISION_INLINE_ALL void halve_baseline(const cv::Mat& gray, cv::Mat* half) {
  halve_rows(gray, half);
}

#if defined(VISION_AVX2)
VISION_AVX2 void halve_avx2(const cv::Mat& gray, cv::Mat* half) {
  halve_rows(gray, half);
}
#endif

}  // namespace

void half_image(const cv::Mat& gray, cv::Mat* half, bool allow_avx2) {
  if (gray.type() != CV_8UC1 || gray.cols < 4 || gray.rows < 4) {
    cv::pyrDown(gray, *half);
    return;
  }
  cv::Mat out((gray.rows + 1) / 2, (gray.cols + 1) / 2, CV_8UC1);
#if defined(VISION_AVX2)
  if (allow_avx2 && cpu_has_avx2()) {
    halve_avx2(gray, &out);
    *half = out;
    return;
  }
#endif
  halve_baseline(gray, &out);
  *half = out;
}

}  // namespace vision::detail
