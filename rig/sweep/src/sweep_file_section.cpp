#include "sweep_file_section.hpp"

#include <cmath>
#include <sstream>

namespace rig::sweep::sweep_file {

// A value as written in the file (strings in double quotes, tables inline),
// on one line, for messages.
std::string repr_full(const toml::node& node) {
  if (const auto* str = node.as_string()) {
    std::string out = "\"";
    for (const char ch : str->get()) {
      if (ch == '"' || ch == '\\') out += '\\';
      if (ch == '\n') {
        out += "\\n";
        continue;
      }
      out += ch;
    }
    return out + "\"";
  }
  if (const auto* array = node.as_array()) {
    std::string out = "[";
    for (std::size_t i = 0; i < array->size(); ++i) {
      out += (i ? ", " : "") + repr_full(*array->get(i));
    }
    return out + "]";
  }
  if (const auto* table = node.as_table()) {
    if (table->empty()) return "{}";
    std::string out = "{ ";
    bool first = true;
    for (const auto& [key, value] : *table) {
      out += (first ? "" : ", ") + std::string(key.str()) + " = " + repr_full(value);
      first = false;
    }
    return out + " }";
  }
  std::ostringstream s;
  node.visit([&](auto&& v) { s << v; });
  return s.str();
}

std::string repr(const toml::node& node) {
  std::string text = repr_full(node);
  if (text.size() > 100) text = text.substr(0, 97) + "...";
  return text;
}

std::string num(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

// A path as written in the file, resolved against the sweep file's folder.
std::string resolve(const fs::path& base_dir, const std::string& path) {
  const fs::path p(path);
  return (p.is_absolute() ? p : base_dir / p).lexically_normal().string();
}

// The key's path resolved, required to name an existing regular file.
std::string existing_file(Section& s, const fs::path& base_dir, const std::string& key,
                          const std::string& what) {
  const std::string written = s.string(key, "the path of " + what);
  const toml::node* node = s.take(key);
  if (written.empty()) s.fail(key, node, "the path of " + what);
  const std::string path = resolve(base_dir, written);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    s.fail(key, node, "the path of " + what + " (relative to the sweep file)",
           path + " is not an existing file");
  }
  return path;
}

}  // namespace rig::sweep::sweep_file
