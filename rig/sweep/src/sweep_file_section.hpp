// Reading one table of a sweep file with checks (sweep_config.cpp's
// helper; not a public header). Every error is a SweepConfigError naming the
// file, the key, the value as written and what was expected.
#pragma once

#include <toml++/toml.h>

#include <cstdint>
#include <filesystem>
#include <set>
#include <string>
#include <utility>

#include "rig/sweep/sweep_config.hpp"

namespace rig::sweep::sweep_file {

namespace fs = std::filesystem;

// A value as written in the file (strings in double quotes, tables inline),
// on one line, for messages.
std::string repr_full(const toml::node& node);
std::string repr(const toml::node& node);
std::string num(double v);

// The keys of one table of the sweep file, read with checks. Every error is a
// SweepConfigError "FILE: TABLE.KEY = VALUE: expected ...". Keys no getter
// asked for are refused by reject_unknown().
class Section {
 public:
  Section(std::string file, std::string name, const toml::table* table)
      : file_(std::move(file)), name_(std::move(name)), table_(table) {}

  std::string field(const std::string& key) const {
    return name_.empty() ? key : key.empty() ? name_ : name_ + "." + key;
  }
  // "FILE: TABLE.KEY = VALUE: [PROBLEM; ]expected EXPECTED"; a missing value
  // (nullptr) is the problem "missing".
  [[noreturn]] void fail(const std::string& key, const toml::node* value,
                         const std::string& expected, const std::string& problem = "") const {
    std::string message = file_ + ": " + field(key);
    if (value != nullptr) message += " = " + repr(*value);
    message += ": ";
    if (value == nullptr) message += "missing; ";
    if (!problem.empty()) message += problem + "; ";
    throw SweepConfigError(message + "expected " + expected);
  }

  bool has(const std::string& key) const { return table_ && table_->contains(key); }
  // The node at key (marked read), or nullptr.
  const toml::node* take(const std::string& key) {
    read_.insert(key);
    return table_ ? table_->get(key) : nullptr;
  }
  const toml::node& need(const std::string& key, const std::string& expected) {
    const toml::node* n = take(key);
    if (n == nullptr) fail(key, nullptr, expected);
    return *n;
  }

  std::int64_t integer(const std::string& key, std::int64_t min, std::int64_t max) {
    const std::string expected =
        "an integer in " + std::to_string(min) + ".." + std::to_string(max);
    const toml::node& n = need(key, expected);
    const auto v = n.value_exact<std::int64_t>();
    if (!v || *v < min || *v > max) fail(key, &n, expected);
    return *v;
  }
  std::int64_t integer_or(const std::string& key, std::int64_t dflt, std::int64_t min,
                          std::int64_t max) {
    return has(key) ? integer(key, min, max) : (take(key), dflt);
  }
  // A finite number accepted by `ok`, described by `expected`.
  template <typename Ok>
  double number(const std::string& key, const std::string& expected, Ok ok) {
    const toml::node& n = need(key, expected);
    const auto v = n.is_number() ? n.value<double>() : std::nullopt;
    if (!v || !std::isfinite(*v) || !ok(*v)) fail(key, &n, expected);
    return *v;
  }
  bool boolean_or(const std::string& key, bool dflt) {
    const toml::node* n = take(key);
    if (n == nullptr) return dflt;
    const auto v = n->value_exact<bool>();
    if (!v) fail(key, n, "true or false");
    return *v;
  }
  std::string string(const std::string& key, const std::string& expected) {
    const toml::node& n = need(key, expected);
    const auto v = n.value_exact<std::string>();
    if (!v) fail(key, &n, expected);
    return *v;
  }
  std::string string_or(const std::string& key, const std::string& dflt,
                        const std::string& expected) {
    return has(key) ? string(key, expected) : (take(key), dflt);
  }
  // An array of `count` finite numbers (count_max > count allows a range of sizes).
  std::vector<double> numbers(const std::string& key, std::size_t count, std::size_t count_max,
                              const std::string& expected) {
    const toml::node& n = need(key, expected);
    const toml::array* a = n.as_array();
    if (a == nullptr || a->size() < count || a->size() > count_max) fail(key, &n, expected);
    std::vector<double> out;
    for (const toml::node& e : *a) {
      const auto v = e.is_number() ? e.value<double>() : std::nullopt;
      if (!v || !std::isfinite(*v)) fail(key, &n, expected);
      out.push_back(*v);
    }
    return out;
  }
  // The sub-table at key (marked read), or nullptr when absent.
  const toml::table* table(const std::string& key) {
    const toml::node* n = take(key);
    if (n != nullptr && !n->is_table()) fail(key, n, "a table [" + field(key) + "]");
    return n ? n->as_table() : nullptr;
  }
  void reject_unknown(const std::string& accepted) const {
    if (!table_) return;
    for (const auto& [key, value] : *table_) {
      if (!read_.count(std::string(key.str()))) {
        fail(std::string(key.str()), &value, "one of " + accepted, "unknown key (misspelt?)");
      }
    }
  }
  const std::string& file() const { return file_; }

 private:
  std::string file_;
  std::string name_;
  const toml::table* table_;
  std::set<std::string> read_;
};

// A path as written in the file, resolved against the sweep file's folder.
std::string resolve(const fs::path& base_dir, const std::string& path);
// The key's path resolved, required to name an existing regular file.
std::string existing_file(Section& s, const fs::path& base_dir, const std::string& key,
                          const std::string& what);

// Runs `load`, turning any error of the file it reads into a SweepConfigError
// that names the sweep file and the key.
template <typename Load>
auto load_named(Section& s, const std::string& key, const std::string& what, Load load) {
  try {
    return load();
  } catch (const std::exception& e) {
    s.fail(key, s.take(key), what, std::string("it does not load: ") + e.what());
  }
}

}  // namespace rig::sweep::sweep_file
