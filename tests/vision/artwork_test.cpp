// vision::artwork: true physical size of SVG/PDF pages, PNG pixel size at a
// dpi, and the marker cells read back from the PNG raster.
#include "vision/artwork.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "file_bytes.hpp"
#include "vision/image_codecs.hpp"

namespace vision {
namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("rig_artwork_test_" + name)).string();
}

constexpr double kPtPerMm = 72.0 / 25.4;

// 50 mm marker, 1-cell quiet zone: a page of 50 * 8 / 6 = 66.667 mm.
constexpr double kPageMm = 50.0 * 8 / 6;

// Tolerance: cairo prints lengths with 6 significant digits (about 1e-4 mm on
// a 189 pt page); 0.01 mm is far below what a printer or a ruler resolves.
TEST(Artwork, SvgMarkerPageHasTheTruePhysicalSize) {
  const std::string path = temp_path("marker.svg");
  write_marker_artwork(Codebook(), 3, MarkerArtworkOptions{}, path);
  const std::string svg = rig_test::file_bytes(path);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(svg, m, std::regex("width=\"([0-9.]+)pt\" height=\"([0-9.]+)pt\"")))
      << svg.substr(0, 300);
  EXPECT_NEAR(std::stod(m[1]) / kPtPerMm, kPageMm, 0.01);
  EXPECT_NEAR(std::stod(m[2]) / kPtPerMm, kPageMm, 0.01);
}

TEST(Artwork, PdfMarkerPageHasTheTruePhysicalSize) {
  const std::string path = temp_path("marker.pdf");
  MarkerArtworkOptions o;
  o.side_mm = 80;
  o.quiet_cells = 2;
  write_marker_artwork(Codebook(), 0, o, path);
  const std::string pdf = rig_test::file_bytes(path);
  ASSERT_EQ(pdf.rfind("%PDF", 0), 0u);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(pdf, m, std::regex("/MediaBox \\[ *0 0 ([0-9.]+) ([0-9.]+) *\\]")));
  const double page_mm = 80.0 * 10 / 6;  // 6 cells + 2 x 2 quiet cells
  EXPECT_NEAR(std::stod(m[1]) / kPtPerMm, page_mm, 0.01);
  EXPECT_NEAR(std::stod(m[2]) / kPtPerMm, page_mm, 0.01);
}

TEST(Artwork, PngMarkerHasThePixelSizeOfItsDpi) {
  const std::string path = temp_path("marker_300.png");
  MarkerArtworkOptions o;
  o.dpi = 300;
  write_marker_artwork(Codebook(), 1, o, path);
  const cv::Mat image = vision::imread(path, cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(image.empty());
  const int expected = static_cast<int>(std::lround(kPageMm / 25.4 * 300));  // 787 px
  EXPECT_EQ(image.cols, expected);
  EXPECT_EQ(image.rows, expected);
}

// Each of the 36 cells, sampled at its centre (a cell is 98 px at 600 dpi:
// far from any anti-aliased edge), is black or white as the codebook says,
// and the quiet zone holds nothing darker than the grey label.
TEST(Artwork, PngMarkerCellsReadBackAsTheCodebookBits) {
  const Codebook book;
  const double dpi = 600, px_per_mm = dpi / 25.4, cell_mm = 50.0 / 6;
  for (int id : {0, 7, 34}) {
    const std::string path = temp_path("marker_bits.png");
    write_marker_artwork(book, id, MarkerArtworkOptions{}, path);
    const cv::Mat image = vision::imread(path, cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(image.empty());
    for (int row = 0; row < kMarkerCells; ++row) {
      for (int col = 0; col < kMarkerCells; ++col) {
        const int u = static_cast<int>((cell_mm * (1 + col + 0.5)) * px_per_mm);
        const int v = static_cast<int>((cell_mm * (1 + row + 0.5)) * px_per_mm);
        const bool white = image.at<uint8_t>(v, u) > 128;
        EXPECT_EQ(white, Codebook::marker_cell_is_white(book.code(id), row, col))
            << "id " << id << " cell " << row << "," << col;
      }
    }
    double darkest = 255;
    const int quiet_px = static_cast<int>(cell_mm * px_per_mm) - 2;  // clear of the border's AA
    cv::minMaxLoc(image.rowRange(image.rows - quiet_px, image.rows), &darkest);
    EXPECT_GE(darkest, 0.55 * 255 - 1) << "bottom quiet zone (with the label)";
    cv::minMaxLoc(image.rowRange(0, quiet_px), &darkest);
    EXPECT_EQ(darkest, 255) << "top quiet zone";
  }
}

// The label sits in the quiet zone: it is drawn (some grey pixels) but stays
// out of the half of the quiet zone next to the border.
TEST(Artwork, LabelStaysInTheOuterPartOfTheQuietZone) {
  const std::string path = temp_path("marker_label.png");
  write_marker_artwork(Codebook(), 5, MarkerArtworkOptions{}, path);
  const cv::Mat image = vision::imread(path, cv::IMREAD_GRAYSCALE);
  const int cell_px = static_cast<int>(50.0 / 6 / 25.4 * 600);
  const int border_bottom = image.rows - cell_px;
  double darkest = 255;
  cv::minMaxLoc(image.rowRange(border_bottom + 2, border_bottom + cell_px * 4 / 10), &darkest);
  EXPECT_EQ(darkest, 255);
  cv::minMaxLoc(image.rowRange(border_bottom + cell_px * 4 / 10, image.rows), &darkest);
  EXPECT_LT(darkest, 200) << "no label drawn";
}

TEST(Artwork, PaperTargetSheetIsA4WithEveryMarkerWhereTheLayoutSaysAt150Dpi) {
  const Codebook book;
  const Target target = Target::load(RIG_SOURCE_DIR "/config/targets/paper.toml");
  const std::string path = temp_path("paper.png");
  TargetArtworkOptions o;
  o.dpi = 150;
  write_target_artwork(book, target, o, path);
  const cv::Mat image = vision::imread(path, cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(image.empty());
  const double px_per_mm = 150 / 25.4;
  EXPECT_EQ(image.cols, std::lround(210 * px_per_mm));
  EXPECT_EQ(image.rows, std::lround(297 * px_per_mm));
  for (const TargetMarker& m : target.markers) {
    const double cell_mm = m.side_m * 1000 / kMarkerCells;
    const double x0 = (m.centre_m.x() - target.sheet_origin_m.x()) * 1000 - m.side_m * 500;
    const double y0 = (m.centre_m.y() - target.sheet_origin_m.y()) * 1000 - m.side_m * 500;
    for (int row = 0; row < kMarkerCells; ++row) {
      for (int col = 0; col < kMarkerCells; ++col) {
        const int u = static_cast<int>((x0 + (col + 0.5) * cell_mm) * px_per_mm);
        const int v = static_cast<int>((y0 + (row + 0.5) * cell_mm) * px_per_mm);
        EXPECT_EQ(image.at<uint8_t>(v, u) > 128,
                  Codebook::marker_cell_is_white(book.code(m.id), row, col))
            << "id " << m.id << " cell " << row << "," << col;
      }
    }
  }
}

TEST(Artwork, A3SheetPdfHasTheA3Size) {
  Target target = Target::paper_default();
  target.sheet_width_m = 0.297;
  target.sheet_height_m = 0.420;
  target.sheet_origin_m = {-0.1485, -0.210};
  const std::string path = temp_path("a3.pdf");
  write_target_artwork(Codebook(), target, TargetArtworkOptions{}, path);
  std::smatch m;
  const std::string pdf = rig_test::file_bytes(path);
  ASSERT_TRUE(std::regex_search(pdf, m, std::regex("/MediaBox \\[ *0 0 ([0-9.]+) ([0-9.]+) *\\]")));
  EXPECT_NEAR(std::stod(m[1]) / kPtPerMm, 297, 0.01);
  EXPECT_NEAR(std::stod(m[2]) / kPtPerMm, 420, 0.01);
}

TEST(Artwork, UnknownExtensionIsRejectedNamingThePath) {
  try {
    write_marker_artwork(Codebook(), 0, MarkerArtworkOptions{}, temp_path("marker.jpg"));
    FAIL() << "no exception";
  } catch (const ArtworkError& e) {
    EXPECT_NE(std::string(e.what()).find("marker.jpg"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(".png"), std::string::npos) << e.what();
  }
}

TEST(Artwork, UnwritablePathIsAnArtworkErrorNamingTheFile) {
  for (const char* name :
       {"/nonexistent-dir/m.png", "/nonexistent-dir/m.pdf", "/nonexistent-dir/m.svg"}) {
    try {
      write_marker_artwork(Codebook(), 0, MarkerArtworkOptions{}, name);
      ADD_FAILURE() << "no exception for " << name;
    } catch (const ArtworkError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

TEST(Artwork, IdOutsideTheCodebookIsRejected) {
  EXPECT_THROW(write_marker_artwork(Codebook(), 35, MarkerArtworkOptions{}, temp_path("x.svg")),
               ArtworkError);
  EXPECT_THROW(write_marker_artwork(Codebook(), -1, MarkerArtworkOptions{}, temp_path("x.svg")),
               ArtworkError);
}

}  // namespace
}  // namespace vision
