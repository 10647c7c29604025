// The inside of a config::Document (config/reader.hpp): the one place where
// the reader's opaque detail::Node meets toml++.
#pragma once

#include <toml++/toml.h>

#include <filesystem>
#include <string>

#include "config/reader.hpp"

namespace config::detail {

struct Parsed {
  std::string source;  // the path as given
  std::string what;    // the file's role in messages ("the sweep file")
  std::string text;
  Raise raise = nullptr;
  std::filesystem::path folder;  // relative paths in the file start here
  toml::table root;
};

// detail::Node is never defined: a Node* is a toml::node* of a Parsed tree,
// converted here and nowhere else.
inline const Node* opaque(const toml::node* node) {
  return reinterpret_cast<const Node*>(node);
}
inline const toml::node& toml_node(const Node& node) {
  return *reinterpret_cast<const toml::node*>(&node);
}

// Calls `raise`, and throws a plain ConfigError should it return.
[[noreturn]] void raise_with(Raise raise, const std::string& message);

// A value as written in a file, on one line (strings in double quotes, arrays
// and tables inline), cut to 100 characters: the VALUE of a message.
std::string value_text(const toml::node& node);

}  // namespace config::detail
