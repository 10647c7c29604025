// Checked reads of TOML tables (see toml_reader.hpp).
#include "motion/toml_reader.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "motion/errors.hpp"

namespace motion {

toml::table parse_toml(std::string_view text, const std::string& source) {
  try {
    return toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    std::ostringstream msg;
    msg << source << ": line " << e.source().begin.line << ": " << e.description();
    throw ProfileError(msg.str());
  }
}

std::string read_text_file(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw ProfileError(path + ": cannot open " + what);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

TomlTableReader::TomlTableReader(const toml::table& root, std::string source, std::string path,
                                 bool optional)
    : source_(std::move(source)), path_(std::move(path)) {
  if (path_.empty()) {
    table_ = &root;
    return;
  }
  const toml::node* node = root.at_path(path_).node();
  if (!node) {
    if (optional) return;
    fail("", "missing table [" + path_ + "]");
  }
  table_ = node->as_table();
  if (!table_) fail("", "expected a table");
}

void TomlTableReader::fail(const std::string& key, const std::string& what) const {
  const std::string field = path_.empty() ? key : (key.empty() ? path_ : path_ + "." + key);
  throw ProfileError(source_ + ": " + field + ": " + what);
}

const toml::node& TomlTableReader::node(const std::string& key) {
  read_.insert(key);
  const toml::node* n = table_ ? table_->get(key) : nullptr;
  if (!n) fail(key, "missing (required)");
  return *n;
}

std::int64_t TomlTableReader::integer(const std::string& key, std::int64_t min, std::int64_t max) {
  auto v = node(key).value_exact<std::int64_t>();
  if (!v) fail(key, "expected an integer");
  if (*v < min || *v > max) {
    fail(key, std::to_string(*v) + " is outside [" + std::to_string(min) + ", " +
                  std::to_string(max) + "]");
  }
  return *v;
}

double TomlTableReader::number(const std::string& key) {
  auto v = node(key).value<double>();
  if (!v || !std::isfinite(*v)) fail(key, "expected a finite number");
  return *v;
}

double TomlTableReader::positive(const std::string& key) {
  const double v = number(key);
  if (v <= 0) fail(key, std::to_string(v) + " must be > 0");
  return v;
}

std::string TomlTableReader::string(const std::string& key) {
  auto v = node(key).value<std::string>();
  if (!v) fail(key, "expected a string");
  return *v;
}

std::int64_t TomlTableReader::integer_or(const std::string& key, std::int64_t dflt,
                                         std::int64_t min, std::int64_t max) {
  return has(key) ? integer(key, min, max) : dflt;
}

double TomlTableReader::number_or(const std::string& key, double dflt) {
  return has(key) ? number(key) : dflt;
}

double TomlTableReader::positive_or(const std::string& key, double dflt) {
  return has(key) ? positive(key) : dflt;
}

double TomlTableReader::non_negative_or(const std::string& key, double dflt) {
  if (!has(key)) return dflt;
  const double v = number(key);
  if (v < 0) fail(key, std::to_string(v) + " must be >= 0");
  return v;
}

bool TomlTableReader::boolean_or(const std::string& key, bool dflt) {
  if (!has(key)) return dflt;
  auto v = node(key).value<bool>();
  if (!v) fail(key, "expected true or false");
  return *v;
}

const toml::table* TomlTableReader::sub_table(const std::string& key) {
  if (!has(key)) return nullptr;
  const toml::table* t = node(key).as_table();
  if (!t) fail(key, "expected a table");
  return t;
}

void TomlTableReader::reject_unknown() const {
  if (!table_) return;
  for (const auto& [key, value] : *table_) {
    if (!read_.count(std::string(key.str())))
      fail(std::string(key.str()), "unknown key (misspelt?)");
  }
}

}  // namespace motion
