// Printable markers and target sheets with cairo (see vision/artwork.hpp).
#include "vision/artwork.hpp"

#include <cairo-pdf.h>
#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

namespace vision {

namespace {

constexpr double kMmPerInch = 25.4;
constexpr double kPointsPerInch = 72.0;
// Labels: grey, so that they never read as ink to a detector, and kept out of
// the inner 45 % of the quiet zone next to the black border.
constexpr double kLabelGrey = 0.55;
constexpr double kMinQuietZoneForLabelMm = 3.0;

std::string lower_extension(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  const size_t slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

std::string format_mm(double mm) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", std::round(mm * 100) / 100);
  return text;
}

void check_dpi(double dpi) {
  if (!(dpi >= 10 && dpi <= 4800)) {
    throw ArtworkError("dpi = " + format_mm(dpi) + ": expected 10 .. 4800");
  }
}

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* c) const { cairo_destroy(c); }
};

// A page of width_mm x height_mm whose cairo user unit is the millimetre.
class Page {
 public:
  Page(const std::string& path, double width_mm, double height_mm, double dpi)
      : path_(path), format_(artwork_format_from_path(path)) {
    const double pt_per_mm = kPointsPerInch / kMmPerInch;
    double scale = pt_per_mm;
    switch (format_) {
      case ArtworkFormat::kSvg:
        surface_.reset(
            cairo_svg_surface_create(path.c_str(), width_mm * pt_per_mm, height_mm * pt_per_mm));
        break;
      case ArtworkFormat::kPdf:
        surface_.reset(
            cairo_pdf_surface_create(path.c_str(), width_mm * pt_per_mm, height_mm * pt_per_mm));
        break;
      case ArtworkFormat::kPng: {
        check_dpi(dpi);
        const long w = std::lround(width_mm / kMmPerInch * dpi);
        const long h = std::lround(height_mm / kMmPerInch * dpi);
        if (w < 1 || h < 1 || w > 32767 || h > 32767) {
          throw ArtworkError(path + ": a PNG of " + std::to_string(w) + " x " + std::to_string(h) +
                             " px; expected 1 .. 32767 px per side (lower --dpi)");
        }
        surface_.reset(cairo_image_surface_create(CAIRO_FORMAT_RGB24, static_cast<int>(w),
                                                  static_cast<int>(h)));
        scale = dpi / kMmPerInch;
        break;
      }
    }
    check("create");
    cr_.reset(cairo_create(surface_.get()));
    cairo_scale(cr_.get(), scale, scale);
    // White page: the quiet zones are paper, and a PNG starts black.
    // (the whole surface: a PNG's last pixel column may reach past the page).
    cairo_set_source_rgb(cr_.get(), 1, 1, 1);
    cairo_paint(cr_.get());
  }

  cairo_t* cr() const { return cr_.get(); }

  // Writes the file (PDF and SVG are written as they are finished).
  void finish() {
    cr_.reset();
    if (format_ == ArtworkFormat::kPng) {
      cairo_surface_flush(surface_.get());
      const cairo_status_t status = cairo_surface_write_to_png(surface_.get(), path_.c_str());
      if (status != CAIRO_STATUS_SUCCESS) {
        throw ArtworkError(path_ + ": cannot write the PNG (" + cairo_status_to_string(status) +
                           ")");
      }
    }
    cairo_surface_finish(surface_.get());
    check("write");
  }

 private:
  void check(const char* what) const {
    const cairo_status_t status = cairo_surface_status(surface_.get());
    if (status != CAIRO_STATUS_SUCCESS) {
      throw ArtworkError(path_ + ": cannot " + what + " the file (" +
                         cairo_status_to_string(status) + ")");
    }
  }

  std::string path_;
  ArtworkFormat format_;
  std::unique_ptr<cairo_surface_t, SurfaceDeleter> surface_;
  std::unique_ptr<cairo_t, ContextDeleter> cr_;
};

// The marker's cells with its top-left border corner at (x, y), mm: the black
// square, then every white code cell in one path (adjacent cells in one fill
// leave no hairline seams in PDF viewers).
void draw_marker(cairo_t* cr, const MarkerFamily& family, int id, double x, double y,
                 double side_mm) {
  const int n = family.marker_cells();
  const double cell = side_mm / n;
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_rectangle(cr, x, y, side_mm, side_mm);
  cairo_fill(cr);
  cairo_set_source_rgb(cr, 1, 1, 1);
  for (int row = 0; row < n; ++row) {
    for (int col = 0; col < n; ++col) {
      if (family.cell_is_white(id, row, col)) {
        cairo_rectangle(cr, x + col * cell, y + row * cell, cell, cell);
      }
    }
  }
  cairo_set_fill_rule(cr, CAIRO_FILL_RULE_WINDING);
  cairo_fill(cr);
}

// "id N  50 mm" centred under a marker, in the outer part of its quiet zone
// (quiet_mm wide); omitted when the quiet zone is too narrow.
void draw_label(cairo_t* cr, const std::string& text, double centre_x, double marker_bottom_y,
                double quiet_mm) {
  if (quiet_mm < kMinQuietZoneForLabelMm) return;
  const double height = std::min(2.5, 0.35 * quiet_mm);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, height);
  cairo_text_extents_t extents;
  cairo_text_extents(cr, text.c_str(), &extents);
  cairo_set_source_rgb(cr, kLabelGrey, kLabelGrey, kLabelGrey);
  // The glyphs' top sits at 45 % of the quiet zone, their bottom inside it.
  cairo_move_to(cr, centre_x - extents.width / 2 - extents.x_bearing,
                marker_bottom_y + 0.45 * quiet_mm - extents.y_bearing);
  cairo_show_text(cr, text.c_str());
}

std::string marker_label(int id, double side_mm) {
  return "id " + std::to_string(id) + "  " + format_mm(side_mm) + " mm";
}

// The sheet's name and printing instructions along its bottom edge, unless a
// marker's quiet zone reaches there.
void draw_sheet_label(cairo_t* cr, const Target& target, int marker_cells, double width_mm,
                      double height_mm) {
  constexpr double kMm = 1000.0;
  constexpr double kTextMm = 3.0, kMarginMm = 5.0;
  const double top = height_mm - kMarginMm - kTextMm;
  for (const TargetMarker& m : target.markers) {
    const double half_mm = (m.side_m / 2 + target.quiet_cells * m.side_m / marker_cells) * kMm;
    if ((m.centre_m.y() - target.sheet_origin_m.y()) * kMm + half_mm > top) return;
  }
  std::ostringstream text;
  text << (target.name.empty() ? std::string("target") : target.name) << ": "
       << target.markers.size() << " markers, pose marker id " << target.pose_marker_id
       << ", sheet " << format_mm(width_mm) << " x " << format_mm(height_mm)
       << " mm. Print at 100 % (actual size) and check the marker sides with a ruler.";
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, kTextMm);
  cairo_set_source_rgb(cr, kLabelGrey, kLabelGrey, kLabelGrey);
  cairo_move_to(cr, kMarginMm, height_mm - kMarginMm);
  cairo_show_text(cr, text.str().c_str());
}

}  // namespace

ArtworkFormat artwork_format_from_path(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".svg") return ArtworkFormat::kSvg;
  if (ext == ".pdf") return ArtworkFormat::kPdf;
  if (ext == ".png") return ArtworkFormat::kPng;
  throw ArtworkError(path + ": unknown extension \"" + ext + "\"; expected .svg, .pdf or .png");
}

void write_marker_artwork(const Codebook& codebook, int id, const MarkerArtworkOptions& options,
                          const std::string& path) {
  write_marker_artwork(MarkerFamily::from_codebook(codebook), id, options, path);
}

void write_marker_artwork(const MarkerFamily& family, int id, const MarkerArtworkOptions& options,
                          const std::string& path) {
  if (!family.has_id(id)) {
    throw ArtworkError("marker id " + std::to_string(id) + ": expected 0 .. " +
                       std::to_string(family.size() - 1) + " (the ids of " + family.name() + ")");
  }
  if (!(options.side_mm > 0 && options.side_mm <= 2000)) {
    throw ArtworkError("marker size " + format_mm(options.side_mm) + " mm: expected 0 .. 2000 mm");
  }
  if (options.quiet_cells < 0 || options.quiet_cells > 20) {
    throw ArtworkError("quiet zone " + std::to_string(options.quiet_cells) +
                       " cells: expected 0 .. 20");
  }
  const double quiet_mm = options.quiet_cells * options.side_mm / family.marker_cells();
  const double page_mm = options.side_mm + 2 * quiet_mm;
  Page page(path, page_mm, page_mm, options.dpi);
  draw_marker(page.cr(), family, id, quiet_mm, quiet_mm, options.side_mm);
  if (options.label) {
    draw_label(page.cr(), marker_label(id, options.side_mm), page_mm / 2,
               quiet_mm + options.side_mm, quiet_mm);
  }
  page.finish();
}

void write_target_artwork(const Codebook& codebook, const Target& target,
                          const TargetArtworkOptions& options, const std::string& path) {
  if (target.family != MarkerFamily::kDefaultName) {
    throw TargetError("target " + target.name + ": family " + target.family +
                      " given a rig4x4 codebook; expected a rig4x4 target");
  }
  write_target_artwork(MarkerFamily::from_codebook(codebook), target, options, path);
}

void write_target_artwork(const Target& target, const TargetArtworkOptions& options,
                          const std::string& path) {
  target.validate(path);
  write_target_artwork(MarkerFamily::named(target.family), target, options, path);
}

void write_target_artwork(const MarkerFamily& family, const Target& target,
                          const TargetArtworkOptions& options, const std::string& path) {
  target.validate(path);
  for (const TargetMarker& m : target.markers) {
    if (!family.has_id(m.id)) {
      throw TargetError("target " + target.name + ": marker id " + std::to_string(m.id) +
                        " is not in " + family.name() + " (ids 0 .. " +
                        std::to_string(family.size() - 1) + ")");
    }
  }
  constexpr double kMm = 1000.0;
  const double width_mm = target.sheet_width_m * kMm, height_mm = target.sheet_height_m * kMm;
  Page page(path, width_mm, height_mm, options.dpi);
  for (const TargetMarker& m : target.markers) {
    const double side_mm = m.side_m * kMm;
    // Sheet coordinates: target-frame position minus the sheet's top-left corner.
    const double cx = (m.centre_m.x() - target.sheet_origin_m.x()) * kMm;
    const double cy = (m.centre_m.y() - target.sheet_origin_m.y()) * kMm;
    draw_marker(page.cr(), family, m.id, cx - side_mm / 2, cy - side_mm / 2, side_mm);
    if (options.label) {
      draw_label(page.cr(), marker_label(m.id, side_mm), cx, cy + side_mm / 2,
                 target.quiet_cells * side_mm / family.marker_cells());
    }
  }
  if (options.label)
    draw_sheet_label(page.cr(), target, family.marker_cells(), width_mm, height_mm);
  page.finish();
}

}  // namespace vision
