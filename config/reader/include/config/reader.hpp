// The one way rig reads a configuration file: read_text_file (size- and
// type-checked), Document (the parsed TOML of one file) and Table (the keys of
// one table, read with checks). The drive profile, the simulated bench's
// [sim] table, target layouts, rig files, sweep files and the simulated rig
// file are all read with it, so they share one error format and one set of
// rules:
//  - Every error names the file, the key (dotted: capture.frames_per_position,
//    markers[2].side_mm), the value as written and what was expected:
//      FILE: TABLE.KEY = VALUE: [PROBLEM; ]expected WHAT
//      FILE: TABLE.KEY: missing; expected WHAT
//    A TOML syntax error names the file, the line and the column:
//      FILE: line L, column C: DESCRIPTION; expected valid TOML
//  - A key no getter asked for is an error (Table::reject_unknown): a misspelt
//    key never falls back to a default. A key that another reader reads is
//    accepted by name (Table::ignore).
//  - Integers are integers: 3.0 is not accepted where an integer is expected;
//    numbers accept integers and floats, and never inf or nan.
//  - A table keyed by codes (a drive profile's [alarms]) accepts each code in
//    decimal (177) or hex (0xB1), as drive manuals write them.
//  - Relative paths in a file are relative to that file's folder.
// Errors are thrown through the Raise the Document was read with
// (config/error.hpp), so each module keeps its own error type, all of them
// config::ConfigError.
//
// toml++ stays inside this library: its types appear in no public header.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/error.hpp"

namespace config {

// The largest configuration file read, in bytes (1 MiB). Every file read here
// is written by hand: the largest shipped one is a few kB and a drive profile
// with a manual's full alarm list stays within tens of kB. A bigger file is
// the wrong file (a run database, an image, a log) and is refused before it is
// read into memory, echoed in messages or stored with a run.
inline constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t{1} << 20;

// The whole content of the file at `path`, which must be a regular file
// (not a folder, device or FIFO) of at most kMaxFileBytes. `what` says what
// the file was to be, e.g. "the drive profile". Errors go through `raise`:
//   "PATH: is a folder; expected the drive profile, a regular file"
//   "PATH: does not exist; expected the drive profile"
//   "PATH: 5242880 bytes, more than any hand-written file; expected the drive
//    profile, a regular file of at most 1048576 bytes"
std::string read_text_file(const std::string& path, const std::string& what, Raise raise);

// The common message form: "FILE: FIELD = VALUE: [PROBLEM; ]expected EXPECTED",
// or, without a value, "FILE: FIELD: missing; expected EXPECTED" where a
// problem, if given, takes the place of "missing" (an absent key whose
// default does not fit). For checks made after reading (a profile's
// overlapping registers, a target's markers off the sheet), where the value
// is the one in memory.
std::string error_message(const std::string& file, const std::string& field,
                          const std::optional<std::string>& value, const std::string& expected,
                          const std::string& problem = "");

// A number as messages write it: up to 10 significant digits, no trailing zeros.
std::string format_number(double value);

// What a number key must hold: a finite number that `ok` accepts, described
// by `expected` in messages ("a speed in (0, 100] mm/s").
struct NumberRule {
  std::string expected;
  std::function<bool(double)> ok;
};
NumberRule finite_number();  // any finite number
NumberRule positive();       // > 0
NumberRule non_negative();   // >= 0

namespace detail {
struct Parsed;  // a Document's path, text, Raise and toml++ tree
struct Node;    // opaque stand-in for a toml++ node of that tree
}  // namespace detail

class Table;

// One parsed configuration file.
class Document {
 public:
  // Reads the file (read_text_file) and parses it. `what` names the file's role
  // in messages ("the sweep file"); relative paths in it are resolved against
  // its folder. Errors (unreadable, syntax) go through `raise`.
  static Document read(const std::string& path, const std::string& what, Raise raise);
  template <typename Error>
  static Document read(const std::string& path, const std::string& what) {
    return read(path, what, &raise_as<Error>);
  }
  // Parses `text` as if read from `source` (a path, named in messages).
  static Document parse(std::string text, const std::string& source, const std::string& what,
                        Raise raise);
  template <typename Error>
  static Document parse(std::string text, const std::string& source, const std::string& what) {
    return parse(std::move(text), source, what, &raise_as<Error>);
  }

  const std::string& source() const;  // the path as given
  const std::string& text() const;    // the file's bytes
  // The top-level table. Each call gives a Table that has read no key yet.
  Table root() const;

 private:
  explicit Document(std::shared_ptr<const detail::Parsed> parsed) : parsed_(std::move(parsed)) {}
  std::shared_ptr<const detail::Parsed> parsed_;
};

// The keys of one table of a Document, read with checks. Each getter marks
// its key as asked for (whether present or not); reject_unknown() then
// refuses every other key. Every error goes through the Document's Raise.
// A Table keeps its Document's parsed tree alive; copies track the keys
// they were asked for separately.
class Table {
 public:
  // Dotted name in the file: "" for the root, "capture", "sim.faults",
  // "markers[2]".
  const std::string& name() const { return name_; }
  // False for an absent optional_table(): its getters then give their
  // defaults and its required getters report the key missing.
  bool exists() const { return table_ != nullptr; }
  bool has(const std::string& key) const;

  // Required keys: an absent key is "missing". Optional keys (_or): the
  // default when absent, checked like the required ones when present.
  //
  // An integer (never a float) in min..max; `expected` replaces the message's
  // "an integer in MIN..MAX".
  std::int64_t integer(const std::string& key, std::int64_t min, std::int64_t max,
                       const std::string& expected = "");
  std::int64_t integer_or(const std::string& key, std::int64_t dflt, std::int64_t min,
                          std::int64_t max, const std::string& expected = "");
  // A finite number (integer or float) that the rule accepts.
  double number(const std::string& key, const NumberRule& rule = finite_number());
  double number_or(const std::string& key, double dflt, const NumberRule& rule = finite_number());
  std::optional<double> optional_number(const std::string& key,
                                        const NumberRule& rule = finite_number());
  bool boolean(const std::string& key);
  bool boolean_or(const std::string& key, bool dflt);
  // A string; `expected` says what it names ("a camera spec gige:ADDRESS | ...").
  std::string string(const std::string& key, const std::string& expected);
  std::string string_or(const std::string& key, const std::string& dflt,
                        const std::string& expected);
  // One of `options` (expected: "\"grid\", \"csv\" or \"paper\"").
  std::string choice(const std::string& key, const std::vector<std::string>& options);
  std::string choice_or(const std::string& key, const std::string& dflt,
                        const std::vector<std::string>& options);
  // An array of min_count..max_count finite numbers.
  std::vector<double> numbers(const std::string& key, std::size_t min_count, std::size_t max_count,
                              const std::string& expected);
  // An array of min_count..max_count strings (a command's argv).
  std::vector<std::string> strings(const std::string& key, std::size_t min_count,
                                   std::size_t max_count, const std::string& expected);
  // A non-empty path naming an existing regular file, resolved against the
  // file's folder; `what` says what it is ("a drive profile").
  std::string existing_file(const std::string& key, const std::string& what);
  // A path as written in the file, resolved against the file's folder
  // (lexically normalised; an absolute path stays as it is).
  std::string resolve(const std::string& written) const;

  // The sub-table at `key`: required, or (optional_table) absent = a Table
  // that does not exist(). A value that is not a table is an error.
  Table table(const std::string& key);
  Table optional_table(const std::string& key);
  // An array of tables ([[markers]]), at least one, named "KEY[i]".
  std::vector<Table> tables(const std::string& key, const std::string& expected);
  // This whole table as a map from codes to strings, its keys being codes in
  // min..max written in decimal (177) or hex (0xB1, 0xb1). `code` names a code
  // in messages ("an alarm code"), `value_expected` the values ("the alarm's
  // meaning, a string"). The same code written twice (177 and 0xB1) is an
  // error naming both. Marks every key read.
  std::map<std::int64_t, std::string> strings_by_code(std::int64_t min, std::int64_t max,
                                                      const std::string& code,
                                                      const std::string& value_expected);
  // Accepts `key` without reading it: another reader reads it (the [sim]
  // table of a bench file, read by the simulated bench).
  void ignore(const std::string& key);

  // Refuses the first key no getter asked for:
  //   "FILE: TABLE.KEY = VALUE: unknown key (misspelt?); expected one of A, B, C"
  // listing the keys asked for, in the order asked, or `expected` if given.
  void reject_unknown(const std::string& expected = "") const;

  // Raises "FILE: TABLE.KEY = VALUE: [PROBLEM; ]expected EXPECTED" with the
  // key's value as written, or "FILE: TABLE.KEY: missing; ..." (PROBLEM in
  // place of "missing" if given) when the key is absent.
  [[noreturn]] void fail(const std::string& key, const std::string& expected,
                         const std::string& problem = "") const;
  // This table as a TOML document (its sub-tables become [headers]): what a
  // run stores when a rig is given inline in a sweep file.
  std::string to_toml() const;

 private:
  friend class Document;
  Table(std::shared_ptr<const detail::Parsed> parsed, const detail::Node* table, std::string name)
      : parsed_(std::move(parsed)), table_(table), name_(std::move(name)) {}
  // The dotted name of a key of this table ("capture.frames_per_position").
  std::string field(const std::string& key) const;
  const detail::Node* node(const std::string& key) const;  // the key's value, or nullptr
  const detail::Node* take(const std::string& key);        // node(key), marking it asked
  std::int64_t checked_integer(const std::string& key, const detail::Node& node, std::int64_t min,
                               std::int64_t max, const std::string& expected);
  double checked_number(const std::string& key, const detail::Node& node, const NumberRule& rule);

  std::shared_ptr<const detail::Parsed> parsed_;
  const detail::Node* table_;  // a toml::table, or nullptr when absent
  std::string name_;
  std::vector<std::string> asked_;  // in the order asked
};

}  // namespace config
