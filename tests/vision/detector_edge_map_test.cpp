// The candidate stage of the detector (vision/src/detector_quads.cpp) computes
// its steps in less time than their textbook form and promises the same
// result: its halved image is cv::pyrDown's pixel for pixel
// (vision/src/detector_half_image.cpp), its edge map cv::Canny's and its
// dilation cv::dilate's (vision/src/detector_edge_map.cpp), and its smoothing
// and dilation of the edge map leave non-zero exactly the pixels that
// cv::GaussianBlur then cv::dilate leave non-zero. findContours reads nothing
// else, so the candidates are the textbook pipeline's. The promises rest on
// OpenCV's internals (pyrDown's integer kernel and border, Canny's Sobel step,
// border, fixed-point direction test and thresholds, the 3x3 Gaussian's
// smallest weight), which is why they are checked here and not only argued.
// Every image is seeded: the tests are deterministic.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>
#include <string>

#include "detector_internal.hpp"

namespace {

// A camera-like scene: random grey polygons, some cut by the border, blurred
// by 0.8 px and with Gaussian noise of 6 grey levels.
cv::Mat scene(int cols, int rows, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> grey(0, 255);
  cv::Mat image(rows, cols, CV_8UC1, cv::Scalar(grey(rng)));
  std::uniform_int_distribution<int> x(-cols / 4, cols + cols / 4), y(-rows / 4, rows + rows / 4);
  for (int k = 0; k < 40; ++k) {
    std::vector<cv::Point> polygon;
    for (int v = 0; v < 4; ++v)
      polygon.emplace_back(x(rng), y(rng));
    cv::fillPoly(image, std::vector<std::vector<cv::Point>>{polygon}, cv::Scalar(grey(rng)));
  }
  cv::GaussianBlur(image, image, cv::Size(0, 0), 0.8);
  cv::Mat noise(rows, cols, CV_16SC1);
  cv::RNG(seed).fill(noise, cv::RNG::NORMAL, 0, 6);
  cv::Mat noisy;
  cv::add(image, noise, noisy, cv::noArray(), CV_8U);
  return noisy;
}

// A 0/255 map with a fraction `density` of its pixels set, borders included.
cv::Mat sparse_edges(int cols, int rows, double density, unsigned seed) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution on(density);
  cv::Mat edges(rows, cols, CV_8UC1);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      edges.at<std::uint8_t>(r, c) = on(rng) ? 255 : 0;
  return edges;
}

int pixels_that_differ(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat differ;
  cv::compare(a, b, differ, cv::CMP_NE);
  return cv::countNonZero(differ);
}

struct ImageSize {
  int cols, rows;
};
// Half of the paper's 736x571 and of a 5 MP GigE sensor (the candidate stage
// runs at half resolution by default), and small and thin images.
const ImageSize kSizes[] = {{368, 286}, {1224, 1024}, {37, 23}, {5, 5}, {3, 120},
                            {120, 3},   {1, 1},       {1, 9},   {9, 1}};

// Scenes (edges of every direction and strength, noise), pure noise (most
// pixels above any threshold: the non-maximum test everywhere), flat images
// and a vertical step of 6 grey levels (gradient 4 x 6 = 24 on its edge, so
// that the thresholds 23.5 find it only when rounded down, as OpenCV does);
// whole and fractional thresholds and swapped ones (OpenCV takes the larger
// as high); both instruction sets.
TEST(DetectorEdgeMap, CannyEdgesAreOpenCvCannyBitForBit) {
  const std::pair<double, double> thresholds[] = {
      {25, 50},     {0, 0},       {10, 200}, {50, 50},     {60, 30},
      {24.5, 50.7}, {1000, 2000}, {-5, 3},   {23.5, 23.5}, {5000, 1e6}};
  unsigned seed = 1;
  for (bool avx2 : {false, true}) {
    for (const ImageSize& size : kSizes) {
      cv::Mat noise(size.rows, size.cols, CV_8UC1);
      cv::RNG(seed).fill(noise, cv::RNG::UNIFORM, 0, 256);
      const cv::Mat flat(size.rows, size.cols, CV_8UC1, cv::Scalar(77));
      cv::Mat step(size.rows, size.cols, CV_8UC1, cv::Scalar(100));
      step.colRange(size.cols / 2, size.cols).setTo(106);
      for (const auto& [low, high] : thresholds) {
        const cv::Mat image = scene(size.cols, size.rows, seed++);
        for (const cv::Mat& input : {image, noise, flat, step}) {
          vision::DetectorParameters p;
          p.canny_low = low;
          p.canny_high = high;
          cv::Mat ours, theirs;
          vision::detail::canny_edges(input, p, &ours, avx2);
          cv::Canny(input, theirs, low, high, 3, false);
          ASSERT_EQ(ours.size(), theirs.size());
          ASSERT_EQ(ours.type(), theirs.type());
          EXPECT_EQ(pixels_that_differ(ours, theirs), 0)
              << size.cols << "x" << size.rows << ", thresholds " << low << "/" << high
              << (avx2 ? ", AVX2" : ", baseline");
        }
        // Not vacuous: the scenes have edges.
        if (size.cols * size.rows > 1000 && high < 1000) {
          cv::Mat theirs;
          cv::Canny(image, theirs, low, high, 3, false);
          EXPECT_GT(cv::countNonZero(theirs), 0);
        }
      }
    }
  }
}

// Thresholds beyond any int (which OpenCV would convert with undefined
// behaviour) are above every gradient: no edges, on the noise image too.
TEST(DetectorEdgeMap, CannyEdgesAreEmptyAboveTheLargestGradient) {
  cv::Mat noise(286, 368, CV_8UC1);
  cv::RNG(5).fill(noise, cv::RNG::UNIFORM, 0, 256);
  vision::DetectorParameters p;
  p.canny_low = 1e30;
  p.canny_high = 1e40;
  for (bool avx2 : {false, true}) {
    cv::Mat ours;
    vision::detail::canny_edges(noise, p, &ours, avx2);
    EXPECT_EQ(cv::countNonZero(ours), 0);
  }
}

// Every pixel value, every border case: noise images (each pixel independent
// and uniform over 0..255, so every sum of the kernel's range occurs) and
// all-white ones (the largest sums, 16 x 16 x 255), at even and odd widths
// and heights, from the 4x4 the fast path takes (smaller ones go to
// cv::pyrDown itself) to a 5 MP sensor, and a view into a larger image (rows
// not contiguous); both instruction sets.
TEST(DetectorEdgeMap, HalfImageIsOpenCvPyrDownPixelForPixel) {
  const ImageSize sizes[] = {{736, 571}, {2448, 2048}, {737, 572}, {4, 4}, {5, 4}, {4, 5},
                             {6, 7},     {7, 6},       {33, 17},   {3, 9}, {9, 3}};
  unsigned seed = 200;
  for (bool avx2 : {false, true}) {
    for (const ImageSize& size : sizes) {
      cv::Mat noise(size.rows, size.cols, CV_8UC1);
      cv::RNG(seed++).fill(noise, cv::RNG::UNIFORM, 0, 256);
      const cv::Mat white(size.rows, size.cols, CV_8UC1, cv::Scalar(255));
      cv::Mat framed(size.rows + 6, size.cols + 10, CV_8UC1);
      cv::RNG(seed++).fill(framed, cv::RNG::UNIFORM, 0, 256);
      const cv::Mat view = framed(cv::Rect(3, 2, size.cols, size.rows));
      for (const cv::Mat& image : {noise, white, view, scene(size.cols, size.rows, seed++)}) {
        cv::Mat ours, theirs;
        vision::detail::half_image(image, &ours, avx2);
        cv::pyrDown(image, theirs);
        ASSERT_EQ(ours.size(), theirs.size()) << size.cols << "x" << size.rows;
        ASSERT_EQ(ours.type(), theirs.type());
        EXPECT_EQ(pixels_that_differ(ours, theirs), 0)
            << size.cols << "x" << size.rows << (avx2 ? ", AVX2" : ", baseline");
      }
    }
  }
  // On a CPU without AVX2 the allow_avx2 runs take the baseline path again.
  RecordProperty("avx2", vision::detail::cpu_has_avx2() ? "yes" : "no");
}

// Grey noise (every value, so a wrong maximum shows) and sparse 0/255 maps
// (what the detector dilates), squares from 1 to larger than the smallest
// images (the square cut at every border), in place and not; both
// instruction sets.
TEST(DetectorEdgeMap, DilateSquareIsOpenCvDilateValueForValue) {
  unsigned seed = 300;
  for (bool avx2 : {false, true}) {
    for (const ImageSize& size : kSizes) {
      cv::Mat noise(size.rows, size.cols, CV_8UC1);
      cv::RNG(seed).fill(noise, cv::RNG::UNIFORM, 0, 256);
      const cv::Mat sparse = sparse_edges(size.cols, size.rows, 0.05, seed++);
      for (const cv::Mat& image : {noise, sparse}) {
        for (int k : {1, 3, 5, 7, 11}) {
          cv::Mat theirs, ours, in_place = image.clone();
          cv::dilate(image, theirs, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)));
          vision::detail::dilate_square(image, k, &ours, avx2);
          vision::detail::dilate_square(in_place, k, &in_place, avx2);
          ASSERT_EQ(ours.size(), theirs.size());
          EXPECT_EQ(pixels_that_differ(ours, theirs), 0)
              << size.cols << "x" << size.rows << ", " << k << "x" << k
              << (avx2 ? ", AVX2" : ", baseline");
          EXPECT_EQ(pixels_that_differ(in_place, theirs), 0)
              << "in place, " << size.cols << "x" << size.rows << ", " << k << "x" << k;
        }
      }
    }
  }
}

TEST(DetectorEdgeMap, ClosingGapsLeavesTheNonZeroPixelsOfBlurThenDilate) {
  unsigned seed = 100;
  for (const ImageSize& size : kSizes) {
    std::vector<std::pair<std::string, cv::Mat>> maps;
    cv::Mat canny;
    cv::Canny(scene(size.cols, size.rows, seed++), canny, 25, 50, 3, false);
    maps.emplace_back("Canny of a scene", canny);
    for (double density : {0.01, 0.1, 0.5})
      maps.emplace_back("density " + std::to_string(density),
                        sparse_edges(size.cols, size.rows, density, seed++));
    for (const auto& [what, edges] : maps) {
      for (int smooth : {0, 1, 3, 5, 7}) {
        for (int grow : {0, 1, 3, 5}) {
          cv::Mat expected = edges.clone();
          if (smooth > 1) cv::GaussianBlur(expected, expected, cv::Size(smooth, smooth), 0);
          if (grow > 1)
            cv::dilate(expected, expected,
                       cv::getStructuringElement(cv::MORPH_RECT, cv::Size(grow, grow)));
          vision::DetectorParameters p;
          p.smoothing_kernel_px = smooth;
          p.dilation_kernel_px = grow;
          cv::Mat ours = edges.clone();
          vision::detail::close_edge_gaps(p, 1, &ours);
          EXPECT_EQ(pixels_that_differ(ours != 0, expected != 0), 0)
              << size.cols << "x" << size.rows << ", " << what << ", smoothing " << smooth
              << " px, dilation " << grow << " px";
        }
      }
    }
  }
}

}  // namespace
