#include "calibration_yaml.hpp"

#include <cctype>
#include <charconv>
#include <string_view>

#include "vision/camera.hpp"

namespace vision::calibration {

const Node* Node::find(const std::string& key) const {
  if (kind != Kind::kMap) return nullptr;
  for (const auto& [k, v] : entries)
    if (k == key) return &v;
  return nullptr;
}

std::optional<double> parse_number(const std::string& text, bool* integer) {
  *integer = false;
  std::string_view s(text);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty() || s.front() == '+' || (s.front() == '-' && s.size() > 1 && s[1] == '+'))
    return std::nullopt;
  for (const char c : s)
    if (!std::isdigit(static_cast<unsigned char>(c)) && c != '-' && c != '+' && c != '.' &&
        c != 'e' && c != 'E')
      return std::nullopt;
  double value = 0;
  const auto [end, ec] =
      std::from_chars(s.data(), s.data() + s.size(), value, std::chars_format::general);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  *integer = s.find_first_of(".eE") == std::string_view::npos;
  return value;
}

namespace {

bool is_key_start(char c) {
  return std::isalpha(static_cast<unsigned char>(c)) || c == '_';
}
bool is_key_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t'))
    s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t'))
    s.remove_suffix(1);
  return s;
}

// The line without its comment: a '#' at the start or after a blank, outside
// a quoted string (a quote opens one at the start of a token only, so that
// an apostrophe inside plain text does not).
std::string_view strip_comment(std::string_view line) {
  char quote = 0;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    const bool token_start =
        i == 0 || std::string_view(" \t[,:").find(line[i - 1]) != std::string_view::npos;
    if (quote) {
      if (c == '\\' && quote == '"')
        ++i;
      else if (c == quote)
        quote = 0;
    } else if ((c == '"' || c == '\'') && token_start) {
      quote = c;
    } else if (c == '#' && (i == 0 || line[i - 1] == ' ' || line[i - 1] == '\t')) {
      return trim(line.substr(0, i));
    }
  }
  return trim(line);
}

// At most 40 characters of what a line holds, for a message.
std::string excerpt(std::string_view s) {
  return s.size() <= 40 ? std::string(s) : std::string(s.substr(0, 40)) + "...";
}

class Parser {
 public:
  Parser(const std::string& path, const std::string& text) : path_(path) {
    std::size_t start = 0;
    while (start <= text.size()) {
      std::size_t end = text.find('\n', start);
      if (end == std::string::npos) end = text.size();
      std::string line = text.substr(start, end - start);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      lines_.push_back(std::move(line));
      start = end + 1;
    }
  }

  Node parse() {
    skip_header();
    const std::size_t first = next_content();
    if (first == kNone)
      fail(static_cast<int>(lines_.size()), "no KEY: VALUE line", "a calibration");
    if (lines_[first][0] == ' ')
      fail(first, "the first key is indented", "top-level keys at column 1");
    Node root = block(-1, 1);
    return root;
  }

 private:
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);

  [[noreturn]] void fail(std::size_t index, const std::string& problem,
                         const std::string& expected) const {
    fail(static_cast<int>(index + 1), problem, expected);
  }
  [[noreturn]] void fail(int line, const std::string& problem, const std::string& expected) const {
    throw CalibrationError("calibration file '" + path_ + "': line " + std::to_string(line) + ": " +
                           problem + "; expected " + expected);
  }

  // The index of the next line from i_ that holds more than blanks and a
  // comment, or kNone.
  std::size_t next_content() const {
    for (std::size_t k = i_; k < lines_.size(); ++k)
      if (!strip_comment(lines_[k]).empty()) return k;
    return kNone;
  }

  // "%YAML:1.0" (OpenCV's form) or "%YAML 1.x", then "---", both optional.
  void skip_header() {
    std::size_t k = next_content();
    if (k == kNone) return;
    const std::string_view first = strip_comment(lines_[k]);
    if (first.front() == '%') {
      if (first != "%YAML:1.0" && first != "%YAML 1.0" && first != "%YAML 1.1" &&
          first != "%YAML 1.2")
        fail(k, "the directive '" + excerpt(first) + "'", "%YAML:1.0 or no directive");
      i_ = k + 1;
      k = next_content();
    }
    if (k != kNone && strip_comment(lines_[k]) == "---") i_ = k + 1;
  }

  // The block map whose lines are indented more than parent_indent, all at
  // the indentation of its first line; it ends at the first line indented
  // less, or at the end of the file.
  Node block(int parent_indent, int depth) {
    Node map;
    map.kind = Node::Kind::kMap;
    int indent = -1;
    for (std::size_t k = next_content(); k != kNone; k = next_content()) {
      const std::string& raw = lines_[k];
      const int ind = static_cast<int>(raw.find_first_not_of(' '));
      if (raw[static_cast<std::size_t>(ind)] == '\t')
        fail(k, "a tab in the indentation", "spaces (YAML indents with spaces only)");
      if (ind <= parent_indent) break;
      if (depth > kMaxBlockDepth)
        fail(k, "blocks nested more than " + std::to_string(kMaxBlockDepth) + " levels deep",
             "a calibration (2 levels)");
      if (indent < 0) {
        indent = ind;
        map.line = static_cast<int>(k + 1);
      }
      if (ind != indent)
        fail(k,
             "indented " + std::to_string(ind) + " columns in a block indented " +
                 std::to_string(indent),
             "KEY: VALUE at column " + std::to_string(indent + 1));
      i_ = k + 1;
      entry(k, ind, depth, map);
    }
    return map;
  }

  // One KEY: VALUE line of a block map.
  void entry(std::size_t k, int indent, int depth, Node& map) {
    const std::string_view body = strip_comment(lines_[k]);
    const std::string expected = "KEY: VALUE, a key of letters, digits, '_', '-' or '.'";
    if (body == "---" || body == "...")
      fail(k, "a second YAML document ('" + std::string(body) + "')", "one document");
    if (body.front() == '-')
      fail(k, "a block sequence item '" + excerpt(body) + "'",
           "KEY: VALUE (a sequence is written [a, b, ...])");
    if (!is_key_start(body.front())) fail(k, "'" + excerpt(body) + "' is not KEY: VALUE", expected);
    std::size_t end = 1;
    while (end < body.size() && is_key_char(body[end]))
      ++end;
    if (end >= body.size() || body[end] != ':' ||
        (end + 1 < body.size() && body[end + 1] != ' ' && body[end + 1] != '\t'))
      fail(k, "'" + excerpt(body) + "' is not KEY: VALUE", expected);
    const std::string key(body.substr(0, end));
    if (map.find(key)) fail(k, "key '" + key + "' given twice", "each key once");
    Node v = value(k, indent, depth, trim(body.substr(end + 1)));
    map.entries.emplace_back(key, std::move(v));
  }

  // The value of the KEY: line k (indented `indent`), `rest` after the ':'.
  Node value(std::size_t k, int indent, int depth, std::string_view rest) {
    const std::string scalar = "a number, a string, [a, b, ...] or an indented block of KEY: VALUE";
    if (rest.empty() || rest.front() == '!') {
      std::string tag;
      if (!rest.empty()) {
        const std::string_view name = rest.substr(0, rest.find_first_of(" \t"));
        if (name != "!!opencv-matrix")
          fail(k, "the tag '" + excerpt(name) + "'", "!!opencv-matrix or no tag");
        if (!trim(rest.substr(name.size())).empty())
          fail(k, "a value on the line of !!opencv-matrix",
               "its rows, cols, dt and data on the indented lines below");
        tag = "opencv-matrix";
      }
      Node b = block(indent, depth + 1);
      const std::size_t next = next_content();
      if (b.entries.empty() && next != kNone) {
        const std::string_view body = strip_comment(lines_[next]);
        if (body.front() == '-')
          fail(next, "a block sequence item '" + excerpt(body) + "'",
               "KEY: VALUE (a sequence is written [a, b, ...])");
      }
      if (b.entries.empty())
        fail(k, tag.empty() ? "a key with no value" : "!!opencv-matrix with no block below",
             tag.empty() ? scalar : "rows, cols, dt and data on indented lines");
      b.tag = tag;
      return b;
    }
    if (rest.front() == '[') return flow_sequence(k, rest);
    if (rest.front() == '{') return flow_mapping(k, rest);
    if (std::string_view("&*|>?@`%,]}").find(rest.front()) != std::string_view::npos)
      fail(k,
           "'" + std::string(1, rest.front()) + "' (an anchor, alias, block scalar or indicator)",
           scalar);
    std::size_t pos = 0;
    Node v = scalar_at(k, rest, pos, /*in_flow=*/false);
    if (pos != rest.size())
      fail(k, "'" + excerpt(rest.substr(pos)) + "' after the value", "one value per key");
    return v;
  }

  // A scalar at rest[pos]: quoted, or plain up to the end (or, in a flow
  // sequence, up to ',' or ']'); pos is left after it.
  Node scalar_at(std::size_t k, std::string_view rest, std::size_t& pos, bool in_flow) {
    Node v;
    v.line = static_cast<int>(k + 1);
    const char q = rest[pos];
    if (q == '"' || q == '\'') {
      for (++pos; pos < rest.size(); ++pos) {
        if (q == '"' && rest[pos] == '\\' && pos + 1 < rest.size()) {
          v.text += rest[++pos];
        } else if (rest[pos] == q) {
          if (q == '\'' && pos + 1 < rest.size() && rest[pos + 1] == '\'') {
            v.text += rest[++pos];
            continue;
          }
          ++pos;
          while (pos < rest.size() && rest[pos] == ' ')
            ++pos;
          return v;
        } else {
          v.text += rest[pos];
        }
      }
      fail(k, "a quoted string not closed on its line", "the closing " + std::string(1, q));
    }
    const std::size_t end = in_flow ? rest.find_first_of(",]", pos) : rest.size();
    const std::string_view plain = trim(rest.substr(pos, end - pos));
    if (plain.empty()) fail(k, "an empty item", "a number or a string");
    if (plain.find(": ") != std::string_view::npos || plain.back() == ':')
      fail(k, "a second ':' in '" + excerpt(plain) + "'", "one KEY: VALUE per line");
    if (in_flow && plain.find_first_of("[{") != std::string_view::npos)
      fail(k, "a collection inside a sequence", "numbers or strings separated by ','");
    v.text = std::string(plain);
    v.number = parse_number(v.text, &v.integer);
    pos = end == std::string_view::npos ? rest.size() : end;
    return v;
  }

  // {KEY: VALUE, ...} from line k on (ROS's `{rows: 3, cols: 3, data: [...]}`),
  // which may continue over the next lines; each value a scalar or [a, b, ...].
  Node flow_mapping(std::size_t k, std::string_view first) {
    std::string text(first.substr(1));
    while (text.find('}') == std::string::npos) {
      if (i_ >= lines_.size())
        fail(k, "a mapping '{' with no closing '}'", "'}' at the end of the mapping");
      text += ' ';
      text += strip_comment(lines_[i_++]);
    }
    const std::size_t close = text.find('}');
    if (!trim(std::string_view(text).substr(close + 1)).empty())
      fail(k, "'" + excerpt(trim(std::string_view(text).substr(close + 1))) + "' after the mapping",
           "nothing after '}'");
    Node map;
    map.kind = Node::Kind::kMap;
    map.line = static_cast<int>(k + 1);
    const std::string_view body = std::string_view(text).substr(0, close);
    std::size_t pos = 0;
    while (pos < body.size()) {
      const std::size_t colon = body.find(':', pos);
      if (colon == std::string_view::npos)
        fail(k, "'" + excerpt(trim(body.substr(pos))) + "' in a mapping", "KEY: VALUE");
      const std::string key(trim(body.substr(pos, colon - pos)));
      if (key.empty() || !is_key_start(key.front()))
        fail(k, "'" + excerpt(key) + "' is not a key", "a key of letters, digits, '_', '-', '.'");
      for (const char c : key)
        if (!is_key_char(c)) fail(k, "'" + excerpt(key) + "' is not a key", "a key of letters");
      if (map.find(key)) fail(k, "key '" + key + "' given twice", "each key once");
      std::size_t v = colon + 1;
      while (v < body.size() && body[v] == ' ')
        ++v;
      std::size_t end = body.find(',', v);
      if (v < body.size() && body[v] == '[') {
        const std::size_t bracket = body.find(']', v);
        if (bracket == std::string_view::npos)
          fail(k, "a sequence '[' with no closing ']'", "']' at the end of the sequence");
        map.entries.emplace_back(key, flow_sequence(k, body.substr(v, bracket + 1 - v)));
        end = body.find(',', bracket);
      } else {
        const std::string_view item =
            trim(body.substr(v, end == std::string_view::npos ? std::string_view::npos : end - v));
        if (item.empty() || item.front() == '{')
          fail(k, "'" + excerpt(item) + "' as the value of '" + key + "'",
               "a number, a string or [a, b, ...]");
        std::size_t p = 0;
        Node value = scalar_at(k, item, p, /*in_flow=*/false);
        if (p != item.size())
          fail(k, "'" + excerpt(item.substr(p)) + "' after the value", "one value per key");
        map.entries.emplace_back(key, std::move(value));
      }
      if (end == std::string_view::npos) break;
      pos = end + 1;
    }
    return map;
  }

  // [a, b, ...] from line k on, which may continue over the next lines.
  Node flow_sequence(std::size_t k, std::string_view first) {
    Node seq;
    seq.kind = Node::Kind::kSequence;
    seq.line = static_cast<int>(k + 1);
    std::string_view rest = first.substr(1);
    std::size_t pos = 0, line = k;
    bool need_item = false;  // after a ','
    for (;;) {
      while (pos < rest.size() && (rest[pos] == ' ' || rest[pos] == '\t'))
        ++pos;
      if (pos == rest.size()) {  // the sequence goes on on the next line
        if (i_ >= lines_.size())
          fail(k, "a sequence '[' with no closing ']'", "']' at the end of the sequence");
        line = i_++;
        rest = strip_comment(lines_[line]);
        pos = 0;
        continue;
      }
      if (rest[pos] == ']') {
        if (!trim(rest.substr(pos + 1)).empty())
          fail(line, "'" + excerpt(trim(rest.substr(pos + 1))) + "' after the sequence",
               "nothing after ']'");
        return seq;
      }
      if (!seq.items.empty() && !need_item) {
        if (rest[pos] != ',') fail(line, "'" + excerpt(rest.substr(pos)) + "'", "',' or ']'");
        ++pos;
        need_item = true;
        continue;
      }
      if (rest[pos] == ',') fail(line, "an empty item", "a number or a string");
      if (rest[pos] == '[' || rest[pos] == '{')
        fail(line, "a collection inside a sequence", "numbers or strings separated by ','");
      seq.items.push_back(scalar_at(line, rest, pos, /*in_flow=*/true));
      need_item = false;
    }
  }

  const std::string& path_;
  std::vector<std::string> lines_;
  std::size_t i_ = 0;
};

}  // namespace

Node parse_yaml(const std::string& path, const std::string& text) {
  return Parser(path, text).parse();
}

}  // namespace vision::calibration
