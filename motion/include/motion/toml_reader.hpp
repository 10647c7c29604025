// motion::TomlTableReader: reads the keys of one TOML table with checks, and
// refuses the keys it was not asked for, so that a misspelt key in a profile
// never silently falls back to a default. Every error is a ProfileError
// "SOURCE: TABLE.KEY: what is wrong". Used by the drive profile and by the
// simulated bench's [sim] table.
#pragma once

#include <toml++/toml.h>

#include <cstdint>
#include <set>
#include <string>
#include <string_view>

namespace motion {

// Parses TOML text. A syntax error throws ProfileError "SOURCE: line N: ...".
toml::table parse_toml(std::string_view text, const std::string& source);
// The whole content of a file. Throws ProfileError "PATH: cannot open WHAT".
std::string read_text_file(const std::string& path, const std::string& what);

class TomlTableReader {
 public:
  // `path`: dotted table name ("motion", "sim.x"), or "" for the root.
  // A missing table is an error unless `optional`, in which case every
  // getter returns its default.
  TomlTableReader(const toml::table& root, std::string source, std::string path,
                  bool optional = false);

  [[noreturn]] void fail(const std::string& key, const std::string& what) const;

  // Required keys.
  std::int64_t integer(const std::string& key, std::int64_t min, std::int64_t max);
  double number(const std::string& key);    // finite
  double positive(const std::string& key);  // finite, > 0
  std::string string(const std::string& key);

  // Optional keys: the default when absent; checked like the above when present.
  std::int64_t integer_or(const std::string& key, std::int64_t dflt, std::int64_t min,
                          std::int64_t max);
  double number_or(const std::string& key, double dflt);
  double positive_or(const std::string& key, double dflt);
  double non_negative_or(const std::string& key, double dflt);
  bool boolean_or(const std::string& key, bool dflt);

  bool has(const std::string& key) const { return table_ && table_->contains(key); }
  // The sub-table at `key` of this table, or nullptr when absent; marks it read.
  const toml::table* sub_table(const std::string& key);
  const std::string& path() const { return path_; }

  // Throws for the first key of the table that no getter asked for.
  void reject_unknown() const;

 private:
  const toml::node& node(const std::string& key);

  std::string source_;
  std::string path_;
  const toml::table* table_ = nullptr;
  std::set<std::string> read_;
};

}  // namespace motion
