// The self-contained report page (see html_page.hpp).
#include "db/report/html_page.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "svg_detail.hpp"

namespace db::report::html {
namespace {

// Screen and print styles. Print: black on white, no page break inside a
// figure or table or right after a heading; table cell classes stay apart
// without colour (better: bold, worse: underlined, paper: italic).
constexpr const char* kStyle = R"css(
:root { color-scheme: light; }
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif;
  margin: 0 auto; max-width: 1100px; padding: 1rem 1.5rem 3rem; color: #111; background: #fff;
  line-height: 1.45; }
h1 { font-size: 1.7rem; margin: 0.5rem 0 1rem; }
h2 { font-size: 1.35rem; margin-top: 2rem; border-bottom: 1px solid #ccc; padding-bottom: 0.2rem; }
h3 { font-size: 1.15rem; margin-top: 1.5rem; }
h4, h5, h6 { font-size: 1rem; margin-top: 1.2rem; }
nav.toc { border: 1px solid #ccc; background: #f7f7f7; padding: 0.5rem 1rem; margin: 1rem 0 2rem; }
nav.toc .toc-title { font-weight: bold; margin: 0.2rem 0; }
nav.toc ol { margin: 0.2rem 0; padding-left: 1.4rem; }
a { color: #0b5394; }
figure.plot { margin: 1.5rem 0; }
figure.plot svg { display: block; max-width: 100%; height: auto; }
figure.frame { display: inline-block; vertical-align: top; margin: 0.5rem 1rem 0.5rem 0; max-width: 100%; }
figure.frame img { display: block; max-width: 100%; height: auto; }
figure.frame figcaption { max-width: 24rem; }
figcaption { font-size: 0.92rem; color: #333; margin-top: 0.4rem; max-width: 60rem; }
table { border-collapse: collapse; margin: 1rem 0 1.5rem; font-size: 0.92rem; }
caption { caption-side: top; text-align: left; font-weight: bold; padding-bottom: 0.3rem; }
th, td { border: 1px solid #bbb; padding: 0.2rem 0.5rem; vertical-align: top; }
thead th { background: #eee; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
td.better { background: #e2f2e2; font-weight: 600; }
td.worse { background: #f9e0e0; text-decoration: underline; }
td.paper { color: #444; font-style: italic; }
.table-wrap { max-width: 100%; overflow-x: auto; }
details.table { margin: 1rem 0; }
details.table > summary { cursor: pointer; font-weight: bold; }
dl.facts { display: grid; grid-template-columns: max-content minmax(0, 1fr); gap: 0.15rem 1rem;
  margin: 1rem 0; }
dl.facts dt { font-weight: bold; }
dl.facts dd { margin: 0; overflow-wrap: anywhere; }
@media print {
  body { max-width: none; padding: 0; color: #000; background: #fff; font-size: 10.5pt; }
  a { color: #000; text-decoration: none; }
  nav.toc { background: none; }
  figure, table, pre { break-inside: avoid; page-break-inside: avoid; }
  .table-wrap { overflow: visible; }
  h1, h2, h3, h4, h5, h6, caption { break-after: avoid; page-break-after: avoid; }
  thead { display: table-header-group; }
  td.better, td.worse, thead th { background: none; }
}
@page { margin: 15mm; }
)css";

// The load check (see html_page.hpp). Pure DOM, no external code; it only
// writes data- attributes, so a failure here cannot change what is read.
constexpr const char* kLoadCheck = R"js(
(function () {
  function check() {
    var figures = document.querySelectorAll('figure.plot');
    var rendered = 0, empty = 0;
    for (var i = 0; i < figures.length; ++i) {
      var svg = figures[i].querySelector('svg');
      var ok = false;
      if (svg) {
        var box = svg.getBBox();
        var marks = svg.querySelectorAll('.mark');
        var visible = 0;
        for (var k = 0; k < marks.length; ++k) {
          var b = marks[k].getBBox();
          if (b.width > 0 || b.height > 0) ++visible;
        }
        ok = box.width > 0 && box.height > 0 && visible > 0;
        if (svg.querySelector('.no-data')) ++empty;
      }
      figures[i].setAttribute('data-rendered', ok ? 'yes' : 'no');
      if (ok) ++rendered;
    }
    var body = document.body;
    body.setAttribute('data-figures-total', String(figures.length));
    body.setAttribute('data-figures-rendered', String(rendered));
    body.setAttribute('data-figures-empty', String(empty));
    body.setAttribute('data-page-height', String(Math.ceil(document.documentElement.scrollHeight)));
    body.setAttribute('data-page-width', String(Math.ceil(document.documentElement.scrollWidth)));
    body.setAttribute('data-viewport-width', String(document.documentElement.clientWidth));
  }
  if (document.readyState === 'complete') check(); else window.addEventListener('load', check);
})();
)js";

// Nothing may be fetched; inline style and the inline load check may run.
// A violation is refused and reported on the console, which the browser test reads.
constexpr const char* kContentSecurityPolicy =
    "default-src 'none'; style-src 'unsafe-inline'; script-src 'unsafe-inline'; img-src data:";

bool id_is_valid(const std::string& id) {
  return !id.empty() && std::all_of(id.begin(), id.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.';
  });
}

}  // namespace

// The page's text and the figures' text are escaped alike (XML-safe, control
// characters become spaces): one rule for everything the report writes.
std::string escape(std::string_view text) {
  return svg::detail::escape(text);
}

Page::Page(std::string title) : title_(std::move(title)) {}

void Page::claim_id(const std::string& id, const char* what) {
  if (!id_is_valid(id))
    throw std::invalid_argument(std::string("html::Page: ") + what + " id '" + id +
                                "' must be non-empty and use only A-Z a-z 0-9 - _ .");
  if (std::find(ids_.begin(), ids_.end(), id) != ids_.end())
    throw std::invalid_argument(std::string("html::Page: ") + what + " id '" + id +
                                "' is already used in this page (ids must be unique)");
  ids_.push_back(id);
}

std::string Page::unique_slug(const std::string& text) {
  std::string slug = "sec-";
  for (char c : text) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (std::isalnum(u))
      slug += static_cast<char>(std::tolower(u));
    else if (slug.back() != '-')
      slug += '-';
  }
  while (slug.size() > 4 && slug.back() == '-')
    slug.pop_back();
  std::string candidate = slug;
  for (int n = 2; std::find(ids_.begin(), ids_.end(), candidate) != ids_.end(); ++n)
    candidate = slug + "-" + std::to_string(n);
  return candidate;
}

void Page::heading(int level, const std::string& text, const std::string& id) {
  if (level < 1 || level > 6)
    throw std::invalid_argument("html::Page::heading: level " + std::to_string(level) + " for '" +
                                text + "' must be 1..6");
  const std::string anchor = id.empty() ? unique_slug(text) : id;
  claim_id(anchor, "heading");
  toc_.push_back({level, anchor, text});
  const std::string h = "h" + std::to_string(level);
  body_ += "<" + h + " id=\"" + anchor + "\">" + escape(text) + "</" + h + ">\n";
}

void Page::paragraph(const std::string& text) {
  body_ += "<p>" + escape(text) + "</p>\n";
}

void Page::facts(const std::vector<std::pair<std::string, std::string>>& facts) {
  body_ += "<dl class=\"facts\">\n";
  for (const auto& [term, value] : facts)
    body_ += "<dt>" + escape(term) + "</dt><dd>" + escape(value) + "</dd>\n";
  body_ += "</dl>\n";
}

void Page::table(const Table& t) {
  if (!t.id.empty()) claim_id(t.id, "table");
  const std::string name = t.id.empty() ? "'" + t.caption + "'" : "'" + t.id + "'";
  for (size_t r = 0; r < t.rows.size(); ++r)
    if (!t.header.empty() && t.rows[r].size() != t.header.size())
      throw std::invalid_argument("html::Page::table: table " + name + " row " + std::to_string(r) +
                                  " has " + std::to_string(t.rows[r].size()) + " cells, expected " +
                                  std::to_string(t.header.size()) + " (the header's)");
  if (t.folded) {
    body_ += "<details class=\"table\"><summary>" +
             escape((t.caption.empty() ? std::string("Table") : t.caption) + " (" +
                    std::to_string(t.rows.size()) + " rows)") +
             "</summary>\n";
  }
  body_ += "<div class=\"table-wrap\">\n<table" +
           (t.id.empty() ? std::string() : " id=\"" + t.id + "\"") + ">\n";
  if (!t.caption.empty()) body_ += "<caption>" + escape(t.caption) + "</caption>\n";
  if (!t.header.empty()) {
    body_ += "<thead><tr>";
    for (const std::string& h : t.header)
      body_ += "<th scope=\"col\">" + escape(h) + "</th>";
    body_ += "</tr></thead>\n";
  }
  body_ += "<tbody>\n";
  for (const auto& row : t.rows) {
    body_ += "<tr>";
    for (const Cell& c : row) {
      body_ += "<td";
      if (!c.css_class.empty()) body_ += " class=\"" + escape(c.css_class) + "\"";
      if (!c.title.empty()) body_ += " title=\"" + escape(c.title) + "\"";
      body_ += ">" + escape(c.text) + "</td>";
    }
    body_ += "</tr>\n";
  }
  body_ += "</tbody>\n</table>\n</div>\n";
  if (t.folded) body_ += "</details>\n";
}

void Page::figure(const svg::Figure& f) {
  std::string svg = svg::render_svg(f);  // validates the id first
  claim_id(f.id, "figure");
  body_ += "<figure class=\"plot\" id=\"" + f.id + "\">\n" + svg + "\n";
  if (!f.caption.empty()) body_ += "<figcaption>" + escape(f.caption) + "</figcaption>\n";
  body_ += "</figure>\n";
  ++figure_count_;
}

namespace {

// RFC 4648 base64, with padding.
std::string base64(const std::string& bytes) {
  static const char* const kAlphabet =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 3; ++k)
      v = (v << 8) | (k < n ? static_cast<unsigned char>(bytes[i + k]) : 0u);
    for (std::size_t k = 0; k < 4; ++k)
      out += k <= n ? kAlphabet[(v >> (18 - 6 * k)) & 0x3F] : '=';
  }
  return out;
}

}  // namespace

void Page::picture(const std::string& id, const std::string& png, int width, int height,
                   const std::string& alt, const std::string& caption) {
  if (width < 1 || height < 1)
    throw std::invalid_argument("html::Page::picture " + id + ": size " + std::to_string(width) +
                                " x " + std::to_string(height) + " px; expected at least 1 x 1");
  claim_id(id, "picture");
  body_ += "<figure class=\"frame\" id=\"" + id + "\"><img src=\"data:image/png;base64," +
           base64(png) + "\" width=\"" + std::to_string(width) + "\" height=\"" +
           std::to_string(height) + "\" alt=\"" + escape(alt) + "\">\n";
  if (!caption.empty()) body_ += "<figcaption>" + escape(caption) + "</figcaption>\n";
  body_ += "</figure>\n";
}

void Page::begin_section(const std::string& id, const std::string& title) {
  claim_id(id, "section");
  const int level = std::min(6, 2 + static_cast<int>(open_sections_.size()));
  open_sections_.push_back(id);
  toc_.push_back({level, id, title});
  const std::string h = "h" + std::to_string(level);
  body_ += "<section id=\"" + id + "\">\n<" + h + ">" + escape(title) + "</" + h + ">\n";
}

void Page::end_section() {
  if (open_sections_.empty()) throw std::logic_error("html::Page::end_section: no section is open");
  open_sections_.pop_back();
  body_ += "</section>\n";
}

std::string Page::str() const {
  if (!open_sections_.empty())
    throw std::logic_error("html::Page::str: section '" + open_sections_.back() +
                           "' is still open (call end_section)");
  std::string o;
  o.reserve(body_.size() + 8192);
  o += "<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  o += "<meta http-equiv=\"Content-Security-Policy\" content=\"" +
       std::string(kContentSecurityPolicy) + "\">\n";
  o += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  o += "<title>" + escape(title_) + "</title>\n<style>" + kStyle + "</style>\n</head>\n";
  o += "<body data-figures-expected=\"" + std::to_string(figure_count_) + "\">\n";
  o += "<h1>" + escape(title_) + "</h1>\n";
  if (!toc_.empty()) {
    // Nested ordered lists following the heading levels.
    o += "<nav class=\"toc\" aria-label=\"Contents\">\n<p class=\"toc-title\">Contents</p>\n";
    const int base = std::min_element(toc_.begin(), toc_.end(), [](auto& a, auto& b) {
                       return a.level < b.level;
                     })->level;
    std::vector<bool> item_open;  // one per open <ol>: whether its last <li> is still open
    for (const TocEntry& e : toc_) {
      const size_t depth = static_cast<size_t>(e.level - base + 1);
      while (item_open.size() > depth) {
        o += item_open.back() ? "</li></ol>\n" : "</ol>\n";
        item_open.pop_back();
      }
      if (item_open.size() == depth && item_open.back()) o += "</li>\n";
      while (item_open.size() < depth) {
        if (!item_open.empty() && !item_open.back()) o += "<li>";  // a level was skipped
        if (!item_open.empty()) item_open.back() = true;
        o += "<ol>\n";
        item_open.push_back(false);
      }
      o += "<li><a href=\"#" + e.id + "\">" + escape(e.text) + "</a>";
      item_open.back() = true;
    }
    while (!item_open.empty()) {
      o += item_open.back() ? "</li></ol>\n" : "</ol>\n";
      item_open.pop_back();
    }
    o += "</nav>\n";
  }
  o += body_;
  o += "<script>" + std::string(kLoadCheck) + "</script>\n</body>\n</html>\n";
  return o;
}

}  // namespace db::report::html
