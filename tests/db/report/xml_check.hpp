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

// One pass over a text: each step reads the construct at the cursor (text,
// comment, end tag, start tag) and returns false once it has recorded an
// error, with the elements read so far.
class Parser {
 public:
  explicit Parser(const std::string& s) : s_(s) {}

  Document run() {
    while (i_ < s_.size() && step()) {
    }
    if (!doc_.error.empty()) return doc_;
    if (!open_.empty())
      fail("element <" + doc_.elements[open_.back()].name + "> not closed", 0);
    else if (doc_.elements.empty())
      fail("no element", 0);
    return doc_;
  }

 private:
  bool fail(const std::string& what, size_t at) {
    doc_.error = what + " at offset " + std::to_string(at) + ": '" + s_.substr(at, 40) + "'";
    return false;
  }
  size_t skip_name(size_t j) const {
    while (j < s_.size() && name_char(s_[j]))
      ++j;
    return j;
  }
  size_t skip_space(size_t j) const {
    while (j < s_.size() && std::isspace(static_cast<unsigned char>(s_[j])))
      ++j;
    return j;
  }

  bool step() {
    if (s_[i_] != '<') return text();
    if (s_.compare(i_, 4, "<!--") == 0) return comment();
    if (s_.compare(i_, 2, "<?") == 0 || s_.compare(i_, 2, "<!") == 0)
      return fail("prolog, DOCTYPE or CDATA not expected in an SVG fragment", i_);
    if (s_.compare(i_, 2, "</") == 0) return end_tag();
    return start_tag();
  }

  bool text() {
    const size_t next = s_.find('<', i_);
    const std::string raw =
        s_.substr(i_, next == std::string::npos ? std::string::npos : next - i_);
    if (raw.find('>') != std::string::npos) return fail("'>' in text", i_);
    std::string err;
    const std::string text = decode(raw, err);
    if (!err.empty()) return fail(err, i_);
    if (open_.empty()) {
      if (text.find_first_not_of(" \t\r\n") != std::string::npos)
        return fail("text outside the root element", i_);
    } else {
      doc_.elements[open_.back()].text += text;
    }
    i_ = next == std::string::npos ? s_.size() : next;
    return true;
  }

  bool comment() {
    const size_t end = s_.find("-->", i_);
    if (end == std::string::npos) return fail("unterminated comment", i_);
    i_ = end + 3;
    return true;
  }

  bool end_tag() {
    size_t j = skip_name(i_ + 2);
    const std::string name = s_.substr(i_ + 2, j - i_ - 2);
    j = skip_space(j);
    if (j >= s_.size() || s_[j] != '>') return fail("malformed end tag", i_);
    if (open_.empty() || doc_.elements[open_.back()].name != name)
      return fail("end tag </" + name + "> does not match the open element", i_);
    open_.pop_back();
    if (open_.empty()) root_closed_ = true;
    i_ = j + 1;
    return true;
  }

  bool start_tag() {
    if (root_closed_) return fail("second root element", i_);
    Element e;
    size_t j = skip_name(i_ + 1);
    e.name = s_.substr(i_ + 1, j - i_ - 1);
    if (e.name.empty()) return fail("'<' without a tag name", i_);
    e.depth = static_cast<int>(open_.size());
    bool self_closing = false;
    for (;;) {
      j = skip_space(j);
      if (j >= s_.size()) return fail("unterminated start tag", i_);
      if (s_[j] == '>') {
        ++j;
        break;
      }
      if (s_.compare(j, 2, "/>") == 0) {
        self_closing = true;
        j += 2;
        break;
      }
      if (!attribute(e, j)) return false;
    }
    doc_.elements.push_back(e);
    if (!self_closing)
      open_.push_back(doc_.elements.size() - 1);
    else if (open_.empty())
      root_closed_ = true;
    i_ = j;
    return true;
  }

  // name="value" or name='value' at j, into e; j moves past it.
  bool attribute(Element& e, size_t& j) {
    const size_t a = j;
    j = skip_name(j);
    const std::string attr = s_.substr(a, j - a);
    if (attr.empty() || j >= s_.size() || s_[j] != '=') return fail("malformed attribute", a);
    ++j;
    if (j >= s_.size() || (s_[j] != '"' && s_[j] != '\'')) return fail("unquoted attribute", a);
    const char quote = s_[j];
    const size_t end = s_.find(quote, j + 1);
    if (end == std::string::npos) return fail("unterminated attribute value", a);
    const std::string raw = s_.substr(j + 1, end - j - 1);
    if (raw.find('<') != std::string::npos) return fail("'<' in attribute value", a);
    std::string err;
    const std::string value = decode(raw, err);
    if (!err.empty()) return fail(err, a);
    if (!e.attrs.emplace(attr, value).second) return fail("duplicate attribute " + attr, a);
    j = end + 1;
    return true;
  }

  const std::string& s_;
  Document doc_;
  std::vector<size_t> open_;  // indices into doc_.elements
  bool root_closed_ = false;
  size_t i_ = 0;
};

inline Document parse(const std::string& s) {
  return Parser(s).run();
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
