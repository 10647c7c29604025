// db::html: one self-contained HTML document for a report: inline CSS (screen
// and print), a table of contents, tables and SVG figures. Nothing is fetched:
// no fonts, scripts, style sheets or images from anywhere, and a
// Content-Security-Policy (default-src 'none') makes the browser refuse (and
// report on its console) anything that tries.
//
// A tiny inline script checks, on load, that each figure's <svg> has a
// non-empty bounding box and at least one data mark, and writes the browser's
// verdict into the DOM:
//   <body data-figures-expected="N"            (written by str(), no script needed)
//         data-figures-total="N"               (figures found by the script)
//         data-figures-rendered="M"            (non-empty box and >= 1 visible mark)
//         data-figures-empty="K"               (figures drawn with a "no data" note)
//         data-page-height="H"                 (document height in CSS px, for screenshots)
//         data-page-width="W"                  (document width in CSS px: > the viewport's
//         data-viewport-width="V">              width when something overflows sideways)
// and data-rendered="yes|no" on each <figure>. With scripts disabled the page
// reads the same; only these attributes are missing.
#pragma once

#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "db/report/svg_plot.hpp"

namespace db::report::html {

// Text for HTML element content or a quoted attribute value: & < > " ' are
// replaced by entities. UTF-8 passes through unchanged.
std::string escape(std::string_view text);

struct Cell {
  std::string text;       // escaped
  std::string css_class;  // "", "better", "worse", "paper", "num" (or several, space-separated)
  std::string title;      // tooltip ("" = none), escaped
  // For a writer that shows numbers in other units than it stores them
  // (db::report writes SI to JSON and CSV, mm and µs on the page): the value
  // the text was written from (NaN: not numeric) and the writer's code for
  // its kind (0: none). Page ignores both.
  double value = std::numeric_limits<double>::quiet_NaN();
  int quantity = 0;
};

struct Table {
  std::string id, caption;          // id: unique in the page ("" = none)
  std::vector<std::string> header;  // column headings; every row has this many cells
  std::vector<std::vector<Cell>> rows;
  // Shown folded: <details> with the caption and the row count as its
  // <summary>, opened by the reader (long tables under their summary).
  bool folded = false;
};

// Builds the document in order of the calls; str() writes it. Ids (headings,
// sections, tables, figures) must be unique in the page: a duplicate throws
// std::invalid_argument naming it.
class Page {
 public:
  explicit Page(std::string title);  // the <title> and the page's <h1>

  // <h{level}> (level 1..6, else std::invalid_argument) listed in the table of
  // contents; id "" = generated from the text ("sec-" + slug, made unique).
  void heading(int level, const std::string& text, const std::string& id = "");
  void paragraph(const std::string& text);  // <p>, escaped
  // <dl class="facts">: one <dt>term</dt><dd>value</dd> per pair, escaped
  // (a run's header: what was measured with what).
  void facts(const std::vector<std::pair<std::string, std::string>>& facts);
  // <table> with <caption>, <thead>, <tbody>, in a <div class="table-wrap">
  // that scrolls sideways if the table is wider than the page (the page
  // itself never does); folded: inside <details>. Throws std::invalid_argument
  // naming the table and row when a row has not header.size() cells (if the
  // header is not empty).
  void table(const Table& table);
  // <figure id class="plot"> with svg::render_svg(figure) and a <figcaption>
  // of the caption; throws what render_svg throws.
  void figure(const svg::Figure& figure);
  // <figure id class="frame"> holding the PNG bytes `png` as an <img> of
  // width x height CSS px (a data: URI, so the page stays self-contained;
  // scaled down to the page's width if wider) with `alt` and a <figcaption>.
  // Throws std::invalid_argument for an id already used or a width or height
  // below 1.
  void picture(const std::string& id, const std::string& png, int width, int height,
               const std::string& alt, const std::string& caption);
  // <section id> with a heading one level below the enclosing section (h2 at
  // the top level, at most h6), listed in the table of contents.
  void begin_section(const std::string& id, const std::string& title);
  // Closes the innermost section; std::logic_error if none is open.
  void end_section();

  // The whole self-contained document: <!doctype html>, UTF-8, inline CSS
  // (screen + @media print: no page breaks inside figures/tables, readable in
  // black and white), a table of contents from the headings, the load check
  // script. Throws std::logic_error if a section is still open.
  std::string str() const;

 private:
  struct TocEntry {
    int level;
    std::string id, text;
  };
  void claim_id(const std::string& id, const char* what);
  std::string unique_slug(const std::string& text);

  std::string title_;
  std::string body_;
  std::vector<TocEntry> toc_;
  std::vector<std::string> ids_;
  std::vector<std::string> open_sections_;
  int figure_count_ = 0;
};

}  // namespace db::report::html
