// Reading and parsing configuration files, and the common message form (see
// config/reader.hpp).
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "parsed.hpp"

namespace config {
namespace detail {

void raise_with(Raise raise, const std::string& message) {
  if (raise != nullptr) raise(message);
  throw ConfigError(message);
}

namespace {

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (const char ch : text) {
    if (ch == '\n') {
      out += "\\n";
      continue;
    }
    if (ch == '"' || ch == '\\') out += '\\';
    out += ch;
  }
  return out + "\"";
}

std::string full_text(const toml::node& node) {
  if (const auto* str = node.as_string()) return quoted(str->get());
  if (const auto* array = node.as_array()) {
    std::string out = "[";
    for (std::size_t i = 0; i < array->size(); ++i)
      out += (i ? ", " : "") + full_text(*array->get(i));
    return out + "]";
  }
  if (const auto* table = node.as_table()) {
    if (table->empty()) return "{}";
    std::string out = "{ ";
    bool first = true;
    for (const auto& [key, value] : *table) {
      out += (first ? "" : ", ") + std::string(key.str()) + " = " + full_text(value);
      first = false;
    }
    return out + " }";
  }
  std::ostringstream s;
  node.visit([&](auto&& value) { s << value; });
  return s.str();
}

}  // namespace

std::string value_text(const toml::node& node) {
  std::string text = full_text(node);
  if (text.size() > 100) text = text.substr(0, 97) + "...";
  return text;
}

}  // namespace detail

namespace {

namespace fs = std::filesystem;
using detail::raise_with;

// Refuses a path that is not an existing regular file.
void check_regular_file(const std::string& path, const std::string& what, Raise raise) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (status.type() == fs::file_type::not_found) {
    raise_with(raise, path + ": does not exist; expected " + what);
  }
  if (ec) raise_with(raise, path + ": cannot be read (" + ec.message() + "); expected " + what);
  if (fs::is_directory(status)) {
    raise_with(raise, path + ": is a folder; expected " + what + ", a regular file");
  }
  if (!fs::is_regular_file(status)) {
    raise_with(raise, path + ": is not a regular file (a device, FIFO or socket); expected " +
                          what + ", a regular file");
  }
}

[[noreturn]] void too_big(const std::string& path, const std::string& what, std::uintmax_t size,
                          Raise raise) {
  raise_with(raise, path + ": " + std::to_string(size) +
                        " bytes, more than any hand-written file; expected " + what +
                        ", a regular file of at most " + std::to_string(kMaxFileBytes) + " bytes");
}

}  // namespace

std::string read_text_file(const std::string& path, const std::string& what, Raise raise) {
  check_regular_file(path, what, raise);
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(path, ec);
  if (!ec && size > kMaxFileBytes) too_big(path, what, size, raise);
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    raise_with(raise, path + ": cannot be opened (" + std::strerror(errno) + "); expected " + what);
  }
  // Read in pieces up to the bound, in case the file grew since its size was taken.
  std::string text;
  char piece[1 << 16];
  while (in.read(piece, sizeof piece) || in.gcount() > 0) {
    text.append(piece, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxFileBytes) too_big(path, what, text.size(), raise);
  }
  return text;
}

std::string error_message(const std::string& file, const std::string& field,
                          const std::optional<std::string>& value, const std::string& expected,
                          const std::string& problem) {
  std::string message = file + ": " + field;
  if (value) {
    message += " = " + *value + ": " + (problem.empty() ? "" : problem + "; ");
  } else {
    message += ": " + (problem.empty() ? std::string("missing") : problem) + "; ";
  }
  return message + "expected " + expected;
}

std::string format_number(double value) {
  std::ostringstream s;
  s.precision(10);
  s << value;
  return s.str();
}

NumberRule finite_number() {
  return {"a finite number", [](double) { return true; }};
}
NumberRule positive() {
  return {"a number > 0", [](double v) { return v > 0; }};
}
NumberRule non_negative() {
  return {"a number >= 0", [](double v) { return v >= 0; }};
}

Document Document::read(const std::string& path, const std::string& what, Raise raise) {
  return parse(read_text_file(path, what, raise), path, what, raise);
}

Document Document::parse(std::string text, const std::string& source, const std::string& what,
                         Raise raise) {
  auto parsed = std::make_shared<detail::Parsed>();
  parsed->source = source;
  parsed->what = what;
  parsed->raise = raise;
  parsed->folder = fs::path(source).parent_path();
  try {
    parsed->root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    const toml::source_position at = e.source().begin;
    raise_with(raise, source + ": line " + std::to_string(at.line) + ", column " +
                          std::to_string(at.column) + ": " + std::string(e.description()) +
                          "; expected valid TOML");
  }
  parsed->text = std::move(text);
  return Document(std::move(parsed));
}

const std::string& Document::source() const {
  return parsed_->source;
}
const std::string& Document::text() const {
  return parsed_->text;
}

Table Document::root() const {
  return Table(parsed_, detail::opaque(&parsed_->root), "");
}

}  // namespace config
