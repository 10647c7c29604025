// The CSV tables: one file per table of the document, named after its id,
// RFC 4180 quoting, a header row first.
#include <sstream>

#include "report_document.hpp"

namespace db::report {
namespace {

std::string field(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

void line(std::ostringstream& out, const std::vector<std::string>& cells) {
  for (std::size_t i = 0; i < cells.size(); ++i)
    out << (i ? "," : "") << field(cells[i]);
  out << "\r\n";
}

}  // namespace

std::vector<std::pair<std::string, std::string>> render_csv(const Document& document) {
  std::vector<std::pair<std::string, std::string>> files;
  for (const Section& section : document.sections) {
    for (const Block& b : section.blocks) {
      if (b.kind != Block::Kind::kTable || b.table.id.empty()) continue;
      std::ostringstream out;
      line(out, b.table.header);
      for (const auto& row : b.table.rows) {
        std::vector<std::string> cells;
        for (const html::Cell& c : row)
          cells.push_back(c.text);
        line(out, cells);
      }
      files.emplace_back(b.table.id + ".csv", out.str());
    }
  }
  return files;
}

}  // namespace db::report
