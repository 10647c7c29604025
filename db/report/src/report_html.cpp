// report.html: the document through db::html (self-contained, SVG inline).
#include "report_document.hpp"
#include "report_units.hpp"

namespace db::report {
namespace {

// Tables longer than this are folded under their caption: a screenful of
// rows, so the page reads as summary, figures and short tables first.
constexpr std::size_t kFoldedFromRows = 20;

}  // namespace

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
        case Block::Kind::kTable: {
          html::Table table = display_table(b.table);
          table.folded = table.id != "summary" && table.rows.size() > kFoldedFromRows;
          page.table(table);
          break;
        }
        case Block::Kind::kFacts:
          page.facts(b.facts);
          break;
        case Block::Kind::kFigure:
          page.figure(b.figure);
          break;
        case Block::Kind::kPicture: {
          const FramePicture& p = *b.picture;
          const std::string where = "plan index " + std::to_string(p.frame.plan_index) +
                                    ", frame " + std::to_string(p.frame.frame_index);
          page.picture("frame-p" + std::to_string(p.frame.plan_index) + "-f" +
                           std::to_string(p.frame.frame_index),
                       p.png, p.width, p.height, where,
                       where + ": " + p.frame.reason + ". " + p.drawn);
          break;
        }
      }
    }
    page.end_section();
  }
  return page.str();
}

}  // namespace db::report
