// A minimal XML reader for the figure tests: checks well-formedness (one
// root, tags nest and match, attributes quoted and unique, entities known, no
// '<' in attribute values) and lists the elements with their attributes and
// decoded direct text. Enough for our generated SVG; not a general parser
// (no DTDs, no CDATA).
#pragma once

#include <cctype>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace xml_check {

struct Element {
  std::string name;
  std::map<std::string, std::string> attrs;  // decoded values
  std::string text;                          // decoded character data directly inside
  int depth = 0;                             // 0 for the root
  bool has_class(const std::string& c) const {
    auto it = attrs.find("class");
    if (it == attrs.end()) return false;
    const std::string padded = " " + it->second + " ";
    return padded.find(" " + c + " ") != std::string::npos;
  }
  double number(const std::string& attr) const { return std::atof(attrs.at(attr).c_str()); }
};

struct Document {
  std::string error;  // "" if well-formed, else what and where
  std::vector<Element> elements;
};

// Decodes &amp; &lt; &gt; &quot; &apos; &#39; &#NN; &#xHH; (ASCII only);
// sets `error` on an unknown or unterminated entity.
inline std::string decode(const std::string& s, std::string& error) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '&') {
      out += s[i];
      continue;
    }
    const size_t end = s.find(';', i);
    if (end == std::string::npos) {
      error = "unterminated entity at '" + s.substr(i, 12) + "'";
      return out;
    }
    const std::string name = s.substr(i + 1, end - i - 1);
    static const std::map<std::string, char> kNamed = {
        {"amp", '&'}, {"lt", '<'}, {"gt", '>'}, {"quot", '"'}, {"apos", '\''}};
    if (kNamed.count(name)) {
      out += kNamed.at(name);
    } else if (name.size() > 1 && name[0] == '#') {
      const long code = name[1] == 'x' ? std::strtol(name.c_str() + 2, nullptr, 16)
                                       : std::strtol(name.c_str() + 1, nullptr, 10);
      if (code <= 0 || code > 127) {
        error = "unsupported character reference &" + name + ";";
        return out;
      }
      out += static_cast<char>(code);
    } else {
      error = "unknown entity &" + name + ";";
      return out;
    }
    i = end;
  }
  return out;
}

inline bool name_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == ':' ||
         c == '.';
}

inline Document parse(const std::string& s) {
  Document doc;
  std::vector<size_t> open;  // indices into doc.elements
  bool root_closed = false;
  auto fail = [&](const std::string& what, size_t at) {
    doc.error = what + " at offset " + std::to_string(at) + ": '" + s.substr(at, 40) + "'";
    return doc;
  };
  size_t i = 0;
  while (i < s.size()) {
    if (s[i] != '<') {
      const size_t next = s.find('<', i);
      const std::string raw = s.substr(i, next == std::string::npos ? std::string::npos : next - i);
      if (raw.find('>') != std::string::npos) return fail("'>' in text", i);
      std::string err;
      const std::string text = decode(raw, err);
      if (!err.empty()) return fail(err, i);
      if (open.empty()) {
        if (text.find_first_not_of(" \t\r\n") != std::string::npos)
          return fail("text outside the root element", i);
      } else {
        doc.elements[open.back()].text += text;
      }
      i = next == std::string::npos ? s.size() : next;
      continue;
    }
    if (s.compare(i, 4, "<!--") == 0) {
      const size_t end = s.find("-->", i);
      if (end == std::string::npos) return fail("unterminated comment", i);
      i = end + 3;
      continue;
    }
    if (s.compare(i, 2, "<?") == 0 || s.compare(i, 2, "<!") == 0)
      return fail("prolog, DOCTYPE or CDATA not expected in an SVG fragment", i);
    if (s.compare(i, 2, "</") == 0) {
      size_t j = i + 2;
      while (j < s.size() && name_char(s[j]))
        ++j;
      const std::string name = s.substr(i + 2, j - i - 2);
      while (j < s.size() && std::isspace(static_cast<unsigned char>(s[j])))
        ++j;
      if (j >= s.size() || s[j] != '>') return fail("malformed end tag", i);
      if (open.empty() || doc.elements[open.back()].name != name)
        return fail("end tag </" + name + "> does not match the open element", i);
      open.pop_back();
      if (open.empty()) root_closed = true;
      i = j + 1;
      continue;
    }
    if (root_closed) return fail("second root element", i);
    Element e;
    size_t j = i + 1;
    while (j < s.size() && name_char(s[j]))
      ++j;
    e.name = s.substr(i + 1, j - i - 1);
    if (e.name.empty()) return fail("'<' without a tag name", i);
    e.depth = static_cast<int>(open.size());
    bool self_closing = false;
    for (;;) {
      while (j < s.size() && std::isspace(static_cast<unsigned char>(s[j])))
        ++j;
      if (j >= s.size()) return fail("unterminated start tag", i);
      if (s[j] == '>') {
        ++j;
        break;
      }
      if (s.compare(j, 2, "/>") == 0) {
        self_closing = true;
        j += 2;
        break;
      }
      const size_t a = j;
      while (j < s.size() && name_char(s[j]))
        ++j;
      const std::string attr = s.substr(a, j - a);
      if (attr.empty() || j >= s.size() || s[j] != '=') return fail("malformed attribute", a);
      ++j;
      if (j >= s.size() || (s[j] != '"' && s[j] != '\'')) return fail("unquoted attribute", a);
      const char quote = s[j];
      const size_t end = s.find(quote, j + 1);
      if (end == std::string::npos) return fail("unterminated attribute value", a);
      const std::string raw = s.substr(j + 1, end - j - 1);
      if (raw.find('<') != std::string::npos) return fail("'<' in attribute value", a);
      std::string err;
      const std::string value = decode(raw, err);
      if (!err.empty()) return fail(err, a);
      if (!e.attrs.emplace(attr, value).second) return fail("duplicate attribute " + attr, a);
      j = end + 1;
    }
    doc.elements.push_back(e);
    if (!self_closing)
      open.push_back(doc.elements.size() - 1);
    else if (open.empty())
      root_closed = true;
    i = j;
  }
  if (!open.empty()) return fail("element <" + doc.elements[open.back()].name + "> not closed", 0);
  if (doc.elements.empty()) return fail("no element", 0);
  return doc;
}

// Elements named `name` (any name if "") that have CSS class `css_class` (any if "").
inline std::vector<Element> find(const Document& d, const std::string& name,
                                 const std::string& css_class = "") {
  std::vector<Element> out;
  for (const Element& e : d.elements)
    if ((name.empty() || e.name == name) && (css_class.empty() || e.has_class(css_class)))
      out.push_back(e);
  return out;
}

}  // namespace xml_check
