// report.html: the document through db::html (self-contained, SVG inline).
#include "report_document.hpp"

namespace db::report {

std::string render_html(const Document& document) {
  html::Page page(document.title);
  page.paragraph(
      "Written by rig report. Every figure's numbers are in report.json, every table is a CSV "
      "file beside this page. Paper: Maidi, Didier, Ababsa, Mallem, \"A performance study for "
      "camera pose estimation using visual marker based tracking\", Machine Vision and "
      "Applications 21:365-376 (2010); rows marked paper are its values, measured with its own "
      "camera, marker and bench.");
  for (const Section& section : document.sections) {
    page.begin_section(section.id, section.title);
    for (const Block& b : section.blocks) {
      switch (b.kind) {
        case Block::Kind::kParagraph:
          page.paragraph(b.text);
          break;
        case Block::Kind::kTable:
          page.table(b.table);
          break;
        case Block::Kind::kFigure:
          page.figure(b.figure);
          break;
      }
    }
    page.end_section();
  }
  return page.str();
}

}  // namespace db::report
