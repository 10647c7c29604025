// db::report::html::Page: one self-contained document, a table of contents from the
// headings, escaped text, figures and tables where they were added.
#include "db/report/html_page.hpp"

#include <gtest/gtest.h>

#include <regex>
#include <stdexcept>
#include <string>

#include "svg_builders.hpp"
#include "xml_check.hpp"

namespace {

using db::report::html::Cell;
using db::report::html::Page;
using db::report::html::Table;
using svg_builders::Ax;
using svg_builders::Pts;

db::report::svg::Figure SmallFigure(const std::string& id) {
  db::report::svg::Figure f;
  f.id = id;
  f.title = "Error vs distance";
  f.x = Ax("distance", "m");
  f.y = Ax("error", "mm");
  f.series = {Pts("measured", {1, 2, 3}, {0.1, 0.3, 0.2}, {0.05, 0.05, 0.1})};
  f.caption = "Mean ± 1 σ <per> distance";
  return f;
}

Page FullPage() {
  Page p("Run 12 & 13");
  p.begin_section("accuracy", "Accuracy");
  p.paragraph("Errors are in mm.");
  p.figure(SmallFigure("fig-a"));
  p.heading(3, "By tag size", "by-size");
  p.table({"tab-a",
           "Per solver",
           {"solver", "error (mm)"},
           {{{"IPPE", "", ""}, {"0.12", "num better", ""}}}});
  p.end_section();
  p.begin_section("appendix", "Appendix");
  p.end_section();
  return p;
}

size_t Count(const std::string& haystack, const std::string& needle) {
  size_t n = 0;
  for (size_t at = haystack.find(needle); at != std::string::npos;
       at = haystack.find(needle, at + 1))
    ++n;
  return n;
}

TEST(HtmlEscape, ReplacesMarkupCharacters) {
  EXPECT_EQ(db::report::html::escape("a<b & \"c\" 'd'>"),
            "a&lt;b &amp; &quot;c&quot; &#39;d&#39;&gt;");
  EXPECT_EQ(db::report::html::escape("µm ± σ"), "µm ± σ");
}

TEST(HtmlPage, IsOneUtf8DocumentWithDoctype) {
  const std::string html = FullPage().str();
  EXPECT_EQ(html.rfind("<!doctype html>", 0), 0u);
  EXPECT_NE(html.find("<meta charset=\"utf-8\">"), std::string::npos);
  EXPECT_NE(html.find("<title>Run 12 &amp; 13</title>"), std::string::npos);
  EXPECT_EQ(Count(html, "<html"), 1u);
  EXPECT_NE(html.find("</html>"), std::string::npos);
}

TEST(HtmlPage, FetchesNothing) {
  const std::string html = FullPage().str();
  // No attribute pointing anywhere but into the page itself.
  const std::regex link(R"re(\b(src|href|xlink:href|action|data)\s*=\s*"([^"]*)")re",
                        std::regex::icase);
  for (auto it = std::sregex_iterator(html.begin(), html.end(), link); it != std::sregex_iterator();
       ++it)
    EXPECT_EQ((*it)[2].str().rfind("#", 0), 0u) << "external reference: " << (*it)[0];
  EXPECT_EQ(html.find("@import"), std::string::npos);
  EXPECT_EQ(html.find("url(http"), std::string::npos);
  EXPECT_EQ(html.find("@font-face"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("<img"), std::string::npos);
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  // Every url(...) in CSS or SVG refers to an element of the page.
  const std::regex url(R"re(url\(([^)]*)\))re");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), url); it != std::sregex_iterator();
       ++it)
    EXPECT_EQ((*it)[1].str().rfind("#", 0), 0u) << (*it)[0];
  // The browser is told to refuse anything else.
  EXPECT_NE(html.find("Content-Security-Policy\" content=\"default-src 'none'"), std::string::npos);
}

TEST(HtmlPage, TableOfContentsListsHeadingsInOrderAndNested) {
  const std::string html = FullPage().str();
  const size_t nav = html.find("<nav class=\"toc\"");
  const size_t nav_end = html.find("</nav>");
  ASSERT_NE(nav, std::string::npos);
  const std::string toc = html.substr(nav, nav_end - nav);
  const size_t a = toc.find("<a href=\"#accuracy\">Accuracy</a>");
  const size_t b = toc.find("<a href=\"#by-size\">By tag size</a>");
  const size_t c = toc.find("<a href=\"#appendix\">Appendix</a>");
  ASSERT_NE(a, std::string::npos);
  ASSERT_NE(b, std::string::npos);
  ASSERT_NE(c, std::string::npos);
  EXPECT_LT(a, b);
  EXPECT_LT(b, c);
  // The h3 is in a list nested inside the Accuracy item.
  EXPECT_NE(toc.find("Accuracy</a><ol>"), std::string::npos) << toc;
  EXPECT_EQ(Count(toc, "<ol>"), Count(toc, "</ol>"));
  EXPECT_EQ(Count(toc, "<li>"), Count(toc, "</li>"));
  // And the targets exist.
  EXPECT_NE(html.find("<section id=\"accuracy\">"), std::string::npos);
  EXPECT_NE(html.find("<h3 id=\"by-size\">By tag size</h3>"), std::string::npos);
}

TEST(HtmlPage, SectionsNestHeadingLevels) {
  Page p("t");
  p.begin_section("outer", "Outer");
  p.begin_section("inner", "Inner");
  p.end_section();
  p.end_section();
  const std::string html = p.str();
  EXPECT_NE(html.find("<section id=\"outer\">\n<h2>Outer</h2>"), std::string::npos);
  EXPECT_NE(html.find("<section id=\"inner\">\n<h3>Inner</h3>"), std::string::npos);
}

TEST(HtmlPage, GeneratesUniqueHeadingIds) {
  Page p("t");
  p.heading(2, "Results & notes");
  p.heading(2, "Results & notes");
  const std::string html = p.str();
  EXPECT_NE(html.find("<h2 id=\"sec-results-notes\">Results &amp; notes</h2>"), std::string::npos);
  EXPECT_NE(html.find("<h2 id=\"sec-results-notes-2\">"), std::string::npos);
}

TEST(HtmlPage, EscapesTableTextAndAttributes) {
  Page p("t");
  p.table({"tab", "A <caption>", {"<h>"}, {{{"a<b&c", "num worse", "say \"hi\""}}}});
  const std::string html = p.str();
  EXPECT_NE(html.find("<caption>A &lt;caption&gt;</caption>"), std::string::npos);
  EXPECT_NE(html.find("<th scope=\"col\">&lt;h&gt;</th>"), std::string::npos);
  EXPECT_NE(html.find("<td class=\"num worse\" title=\"say &quot;hi&quot;\">a&lt;b&amp;c</td>"),
            std::string::npos);
  EXPECT_EQ(html.find("a<b"), std::string::npos);
}

TEST(HtmlPage, RejectsRaggedTablesNamingTheRow) {
  Page p("t");
  try {
    p.table({"tab-x", "", {"a", "b"}, {{{"1", "", ""}, {"2", "", ""}}, {{"3", "", ""}}}});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("table 'tab-x' row 1 has 1 cells, expected 2"),
              std::string::npos)
        << e.what();
  }
}

TEST(HtmlPage, ParagraphIsEscaped) {
  Page p("t");
  p.paragraph("<b>x</b>");
  const std::string html = p.str();
  EXPECT_NE(html.find("<p>&lt;b&gt;x&lt;/b&gt;</p>"), std::string::npos);
  EXPECT_EQ(html.find("<b>x</b>"), std::string::npos);
}

TEST(HtmlPage, FigureIsAnInlineSvgWithCaption) {
  Page p("t");
  p.figure(SmallFigure("fig-1"));
  p.figure(SmallFigure("fig-2"));
  const std::string html = p.str();
  EXPECT_NE(html.find("<body data-figures-expected=\"2\">"), std::string::npos);
  const size_t figure = html.find("<figure class=\"plot\" id=\"fig-1\">");
  ASSERT_NE(figure, std::string::npos);
  const size_t svg = html.find("<svg", figure);
  const size_t svg_end = html.find("</svg>", svg);
  const size_t caption = html.find("<figcaption>Mean ± 1 σ &lt;per&gt; distance</figcaption>");
  EXPECT_LT(svg, caption);
  EXPECT_LT(svg_end, caption);
  // The inline SVG is well-formed XML on its own.
  EXPECT_EQ(xml_check::parse(html.substr(svg, svg_end + 6 - svg)).error, "");
}

TEST(HtmlPage, RejectsDuplicateIds) {
  Page p("t");
  p.figure(SmallFigure("same"));
  EXPECT_THROW(p.figure(SmallFigure("same")), std::invalid_argument);
  EXPECT_THROW(p.begin_section("same", "x"), std::invalid_argument);
  EXPECT_THROW(p.heading(2, "x", "same"), std::invalid_argument);
}

TEST(HtmlPage, UnbalancedSectionsAreProgrammingErrors) {
  Page p("t");
  EXPECT_THROW(p.end_section(), std::logic_error);
  p.begin_section("open", "Open");
  EXPECT_THROW(p.str(), std::logic_error);
  EXPECT_THROW(p.heading(7, "too deep"), std::invalid_argument);
}

TEST(HtmlPage, PrintStylesKeepFiguresAndTablesWhole) {
  const std::string html = FullPage().str();
  const size_t print = html.find("@media print");
  ASSERT_NE(print, std::string::npos);
  EXPECT_NE(html.find("break-inside: avoid", print), std::string::npos);
}

TEST(HtmlPage, LoadCheckIsInlineAndWritesTheVerdict) {
  const std::string html = FullPage().str();
  EXPECT_EQ(Count(html, "<script>"), 1u);
  EXPECT_NE(html.find("data-figures-rendered"), std::string::npos);
  EXPECT_NE(html.find("getBBox"), std::string::npos);
}

}  // namespace
