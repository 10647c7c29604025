// Step 1's edge map: cv::Canny(image, edges, low, high, 3, false) bit for bit,
// with the derivatives computed row by row as the edge map reaches them
// instead of into two images first.
//
// OpenCV computes the 3x3 Sobel derivatives into two 16-bit images, then
// their L1 magnitude |dx| + |dy| row by row, keeps the pixels above the low
// threshold that are a maximum across the edge (the direction quantized to
// 0, 45, 90 or 135 degrees by tan 22.5 in 15-bit fixed point), starts edges
// at those above the high threshold and follows them through the kept
// pixels, 8-connected (Canny 1986; OpenCV's modules/imgproc/src/canny.cpp).
// Here the derivatives and the magnitude of a row are computed as the row is
// reached, from three rows of the image padded by replication (Sobel's
// border), into ring buffers; the non-maximum test runs only at the pixels
// above the low threshold, found eight at a time; the rest is the same
// integer arithmetic in the same order, so the kept pixels, the seeds and the
// edges followed are the same.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <opencv2/core.hpp>
#include <vector>

#include "detector_internal.hpp"

namespace vision::detail {
namespace {

// Map states, as OpenCV's: 0 a kept pixel not (yet) on an edge, 1 not an
// edge, 2 on an edge.
constexpr std::uint8_t kKept = 0, kNotEdge = 1, kEdge = 2;

// One row of the derivatives and of the magnitude, and which of its pixels
// exceed the low threshold.
struct GradientRow {
  std::vector<std::int16_t> dx, dy;
  std::vector<std::int16_t> magnitude;  // index 0 is column -1 (0 outside the image)
  std::vector<std::uint8_t> above_low;  // padded to a multiple of 8 with zeros

  explicit GradientRow(int cols)
      : dx(static_cast<std::size_t>(cols)),
        dy(static_cast<std::size_t>(cols)),
        magnitude(static_cast<std::size_t>(cols) + 2, 0),
        above_low(static_cast<std::size_t>(cols) + 8, 0) {}
};

// Sobel at every column of a row from its padded neighbours (up, centre,
// down: cols + 2 pixels, column -1 first), then |dx| + |dy| and the test
// against `low`. The smoothing sums are shared between neighbouring columns:
// dx[j] = across[j + 2] - across[j] with across = up + 2 centre + down,
// dy[j] = rise[j] + 2 rise[j + 1] + rise[j + 2] with rise = down - up. Every
// value fits 16 bits: |dx|, |dy| <= 4 x 255.
inline void gradient_row(const std::uint8_t* __restrict up, const std::uint8_t* __restrict centre,
                         const std::uint8_t* __restrict down, int cols, std::int16_t low,
                         std::int16_t* __restrict across, std::int16_t* __restrict rise,
                         std::int16_t* __restrict dx, std::int16_t* __restrict dy,
                         std::int16_t* __restrict magnitude, std::uint8_t* __restrict above_low) {
  for (int j = 0; j < cols + 2; ++j) {
    across[j] = static_cast<std::int16_t>(up[j] + 2 * centre[j] + down[j]);
    rise[j] = static_cast<std::int16_t>(down[j] - up[j]);
  }
  for (int j = 0; j < cols; ++j) {
    const auto gx = static_cast<std::int16_t>(across[j + 2] - across[j]);
    const auto gy = static_cast<std::int16_t>(rise[j] + 2 * rise[j + 1] + rise[j + 2]);
    dx[j] = gx;
    dy[j] = gy;
    const auto m = static_cast<std::int16_t>((gx < 0 ? -gx : gx) + (gy < 0 ? -gy : gy));
    magnitude[j] = m;
    above_low[j] = m > low;
  }
}

// Whether the pixel at column j of the centre row is a maximum across its
// edge direction (OpenCV's tie rules: strict towards one side, not the other).
inline bool local_maximum(const GradientRow& previous, const GradientRow& centre,
                          const GradientRow& next, int j) {
  constexpr int kTan22 = 13573;  // tan(22.5 deg) x 2^15, as OpenCV's TG22
  const std::int16_t* mp = previous.magnitude.data() + 1;
  const std::int16_t* mc = centre.magnitude.data() + 1;
  const std::int16_t* mn = next.magnitude.data() + 1;
  const int m = mc[j], xs = centre.dx[j], ys = centre.dy[j];
  const int x = std::abs(xs), y = std::abs(ys) << 15;
  const int tg22x = x * kTan22;
  if (y < tg22x) return m > mc[j - 1] && m >= mc[j + 1];  // across: horizontal
  const int tg67x = tg22x + (x << 16);
  if (y > tg67x) return m > mp[j] && m >= mn[j];  // vertical
  const int s = (xs ^ ys) < 0 ? -1 : 1;           // diagonal
  return m > mp[j - s] && m > mn[j + s];
}

struct EdgeMap {
  int cols, rows, step;
  std::vector<std::uint8_t> cells;  // (rows + 2) x (cols + 2), a border of kNotEdge
  std::vector<std::uint8_t*> seeds;

  EdgeMap(int c, int r)
      : cols(c),
        rows(r),
        step(c + 2),
        cells(static_cast<std::size_t>(c + 2) * static_cast<std::size_t>(r + 2), kNotEdge) {}
  std::uint8_t* row(int i) { return cells.data() + static_cast<std::size_t>(i + 1) * step + 1; }
};

// The kept pixels of row i into the map, and the seeds among them (above
// `high`, unless the pixel to the left or above already is one: it will reach
// them).
inline void mark_row(const GradientRow& previous, const GradientRow& centre,
                     const GradientRow& next, int i, int high, EdgeMap* map) {
  std::uint8_t* out = map->row(i);
  const std::int16_t* mc = centre.magnitude.data() + 1;
  bool left_is_seed = false;
  for (int j0 = 0; j0 < map->cols; j0 += 8) {
    std::uint64_t any;
    std::memcpy(&any, centre.above_low.data() + j0, 8);
    if (any == 0) {
      left_is_seed = false;
      continue;
    }
    const int j1 = std::min(j0 + 8, map->cols);
    for (int j = j0; j < j1; ++j) {
      if (centre.above_low[j] && local_maximum(previous, centre, next, j)) {
        if (!left_is_seed && mc[j] > high && out[j - map->step] != kEdge) {
          out[j] = kEdge;
          map->seeds.push_back(out + j);
          left_is_seed = true;
        } else {
          out[j] = kKept;
        }
        continue;
      }
      left_is_seed = false;
    }
  }
}

// Hysteresis: every kept pixel 8-connected to a seed joins the edges.
void follow_edges(EdgeMap* map) {
  const std::ptrdiff_t s = map->step;
  const std::ptrdiff_t around[8] = {-1, 1, -s - 1, -s, -s + 1, s - 1, s, s + 1};
  while (!map->seeds.empty()) {
    std::uint8_t* m = map->seeds.back();
    map->seeds.pop_back();
    for (const std::ptrdiff_t d : around)
      if (m[d] == kKept) {
        m[d] = kEdge;
        map->seeds.push_back(m + d);
      }
  }
}

// The image row i padded by one replicated pixel each side.
void padded_row(const cv::Mat& image, int i, std::uint8_t* out) {
  const std::uint8_t* in = image.ptr<std::uint8_t>(std::clamp(i, 0, image.rows - 1));
  std::memcpy(out + 1, in, static_cast<std::size_t>(image.cols));
  out[0] = in[0];
  out[image.cols + 1] = in[image.cols - 1];
}

// The whole edge map; both ring buffers advance one row at a time.
inline void edge_map(const cv::Mat& image, int low, int high, cv::Mat* edges) {
  const int cols = image.cols, rows = image.rows;
  const auto low16 = static_cast<std::int16_t>(std::clamp(low, -1, 32767));
  std::vector<std::uint8_t> pixels(3 * static_cast<std::size_t>(cols + 2));
  std::uint8_t* padded[3] = {pixels.data(), pixels.data() + cols + 2,
                             pixels.data() + 2 * (cols + 2)};
  GradientRow ring[3] = {GradientRow(cols), GradientRow(cols), GradientRow(cols)};
  std::vector<std::int16_t> across(static_cast<std::size_t>(cols + 2)),
      rise(static_cast<std::size_t>(cols + 2));
  GradientRow* previous = &ring[0];  // row i - 1: magnitude 0 above the image
  GradientRow* centre = &ring[1];
  GradientRow* next = &ring[2];
  EdgeMap map(cols, rows);
  padded_row(image, -1, padded[0]);
  padded_row(image, 0, padded[1]);
  padded_row(image, 1, padded[2]);
  const auto gradient = [&](GradientRow* g, int k) {  // the centre of padded[k]
    gradient_row(padded[(k + 2) % 3], padded[k], padded[(k + 1) % 3], cols, low16, across.data(),
                 rise.data(), g->dx.data(), g->dy.data(), g->magnitude.data() + 1,
                 g->above_low.data());
  };
  gradient(next, 1);  // row 0
  for (int i = 0; i < rows; ++i) {
    std::swap(previous, centre);
    std::swap(centre, next);
    if (i == 0) std::fill(previous->magnitude.begin(), previous->magnitude.end(), 0);
    if (i + 1 < rows) {
      padded_row(image, i + 2, padded[i % 3]);  // row i - 1's slot
      gradient(next, (i + 2) % 3);
    } else {
      std::fill(next->magnitude.begin(), next->magnitude.end(), 0);
    }
    mark_row(*previous, *centre, *next, i, high, &map);
  }
  follow_edges(&map);
  edges->create(rows, cols, CV_8UC1);
  for (int i = 0; i < rows; ++i) {
    const std::uint8_t* m = map.row(i);
    std::uint8_t* e = edges->ptr<std::uint8_t>(i);
    for (int j = 0; j < cols; ++j)
      e[j] = static_cast<std::uint8_t>(-(m[j] >> 1));  // kEdge -> 255, else 0
  }
}

// The largest value in the k x k square around every pixel, the square cut
// where the image ends (cv::dilate's default border adds nothing to a
// maximum): along each row (the row padded by r = k / 2 zeros each side,
// which do not change a maximum of non-negative values), then down each
// column of those row maxima.
inline void dilate_rows(const cv::Mat& image, int k, cv::Mat* out) {
  const int cols = image.cols, rows = image.rows, r = k / 2;
  cv::Mat across(rows, cols, CV_8UC1);
  std::vector<std::uint8_t> padded(static_cast<std::size_t>(cols + 2 * r), 0);
  for (int i = 0; i < rows; ++i) {
    std::memcpy(padded.data() + r, image.ptr<std::uint8_t>(i), static_cast<std::size_t>(cols));
    std::uint8_t* __restrict a = across.ptr<std::uint8_t>(i);
    const std::uint8_t* __restrict p = padded.data();
    std::memcpy(a, p, static_cast<std::size_t>(cols));
    for (int t = 1; t < k; ++t)
      for (int j = 0; j < cols; ++j)
        a[j] = std::max(a[j], p[j + t]);
  }
  out->create(rows, cols, CV_8UC1);
  for (int i = 0; i < rows; ++i) {
    std::uint8_t* __restrict o = out->ptr<std::uint8_t>(i);
    const int first = std::max(i - r, 0), last = std::min(i + r, rows - 1);
    std::memcpy(o, across.ptr<std::uint8_t>(first), static_cast<std::size_t>(cols));
    for (int q = first + 1; q <= last; ++q) {
      const std::uint8_t* __restrict a = across.ptr<std::uint8_t>(q);
      for (int j = 0; j < cols; ++j)
        o[j] = std::max(o[j], a[j]);
    }
  }
}

VISION_INLINE_ALL void dilate_baseline(const cv::Mat& image, int k, cv::Mat* out) {
  dilate_rows(image, k, out);
}

#if defined(VISION_AVX2)
VISION_AVX2 void dilate_avx2(const cv::Mat& image, int k, cv::Mat* out) {
  dilate_rows(image, k, out);
}
#endif

VISION_INLINE_ALL void edge_map_baseline(const cv::Mat& image, int low, int high, cv::Mat* edges) {
  edge_map(image, low, high, edges);
}

#if defined(VISION_AVX2)
VISION_AVX2 void edge_map_avx2(const cv::Mat& image, int low, int high, cv::Mat* edges) {
  edge_map(image, low, high, edges);
}
#endif

}  // namespace

void canny_edges(const cv::Mat& image, const DetectorParameters& p, cv::Mat* edges,
                 bool allow_avx2) {
  CV_Assert(image.type() == CV_8UC1 && !image.empty());
  // OpenCV's thresholds for the L1 gradient: whole grey levels, rounded
  // down, the larger one high. The magnitude lies in 0 .. 2040, so bounding
  // them to +-2^20 changes nothing but keeps the conversion defined.
  constexpr double kBound = 1 << 20;
  int low = static_cast<int>(std::floor(std::clamp(p.canny_low, -kBound, kBound)));
  int high = static_cast<int>(std::floor(std::clamp(p.canny_high, -kBound, kBound)));
  if (low > high) std::swap(low, high);
#if defined(VISION_AVX2)
  if (allow_avx2 && cpu_has_avx2()) {
    edge_map_avx2(image, low, high, edges);
    return;
  }
#endif
  edge_map_baseline(image, low, high, edges);
}

void dilate_square(const cv::Mat& image, int k, cv::Mat* dilated, bool allow_avx2) {
  CV_Assert(image.type() == CV_8UC1 && !image.empty() && k >= 1 && k % 2 == 1);
  cv::Mat out;  // not in place: the column pass reads rows the output replaces
#if defined(VISION_AVX2)
  if (allow_avx2 && cpu_has_avx2()) {
    dilate_avx2(image, k, &out);
    *dilated = out;
    return;
  }
#endif
  dilate_baseline(image, k, &out);
  *dilated = out;
}

}  // namespace vision::detail
