// Checked reads of the keys of one table (see config/reader.hpp).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

#include "parsed.hpp"

namespace config {
namespace {

namespace fs = std::filesystem;
using detail::opaque;
using detail::toml_node;

const toml::table* toml_table(const detail::Node* node) {
  return node ? toml_node(*node).as_table() : nullptr;
}

std::string join(const std::vector<std::string>& items, const std::string& last_separator) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out += i + 1 == items.size() ? last_separator : ", ";
    out += items[i];
  }
  return out;
}

// A code written as a key: decimal without leading zeros, or 0x/0X and hex digits.
std::optional<std::int64_t> parse_code(const std::string& key) {
  const bool hex = key.size() > 2 && key[0] == '0' && (key[1] == 'x' || key[1] == 'X');
  const std::string digits = hex ? key.substr(2) : key;
  const auto is_digit = [&](char ch) {
    const auto c = static_cast<unsigned char>(ch);
    return hex ? std::isxdigit(c) != 0 : std::isdigit(c) != 0;
  };
  if (digits.empty() || digits.size() > 12 || !std::all_of(digits.begin(), digits.end(), is_digit))
    return std::nullopt;
  if (!hex && digits.size() > 1 && digits[0] == '0') return std::nullopt;
  return std::stoll(digits, nullptr, hex ? 16 : 10);
}

std::string integer_expected(std::int64_t min, std::int64_t max, const std::string& expected) {
  return expected.empty() ? "an integer in " + std::to_string(min) + ".." + std::to_string(max)
                          : expected;
}

}  // namespace

std::string Table::field(const std::string& key) const {
  return name_.empty() ? key : name_ + "." + key;
}

bool Table::has(const std::string& key) const {
  return node(key) != nullptr;
}

const detail::Node* Table::node(const std::string& key) const {
  const toml::table* table = toml_table(table_);
  return table ? opaque(table->get(key)) : nullptr;
}

const detail::Node* Table::take(const std::string& key) {
  if (std::find(asked_.begin(), asked_.end(), key) == asked_.end()) asked_.push_back(key);
  return node(key);
}

void Table::fail(const std::string& key, const std::string& expected,
                 const std::string& problem) const {
  const detail::Node* value = node(key);
  const std::optional<std::string> text =
      value ? std::optional<std::string>(detail::value_text(toml_node(*value))) : std::nullopt;
  detail::raise_with(parsed_->raise,
                     error_message(parsed_->source, field(key), text, expected, problem));
}

std::int64_t Table::checked_integer(const std::string& key, const detail::Node& node,
                                    std::int64_t min, std::int64_t max,
                                    const std::string& expected) {
  const auto value = toml_node(node).value_exact<std::int64_t>();
  if (!value || *value < min || *value > max) fail(key, integer_expected(min, max, expected));
  return *value;
}

std::int64_t Table::integer(const std::string& key, std::int64_t min, std::int64_t max,
                            const std::string& expected) {
  const detail::Node* n = take(key);
  if (n == nullptr) fail(key, integer_expected(min, max, expected));
  return checked_integer(key, *n, min, max, expected);
}

std::int64_t Table::integer_or(const std::string& key, std::int64_t dflt, std::int64_t min,
                               std::int64_t max, const std::string& expected) {
  const detail::Node* n = take(key);
  return n ? checked_integer(key, *n, min, max, expected) : dflt;
}

double Table::checked_number(const std::string& key, const detail::Node& node,
                             const NumberRule& rule) {
  const toml::node& n = toml_node(node);
  const auto value = n.is_number() ? n.value<double>() : std::nullopt;
  if (!value || !std::isfinite(*value) || (rule.ok && !rule.ok(*value))) fail(key, rule.expected);
  return *value;
}

double Table::number(const std::string& key, const NumberRule& rule) {
  const detail::Node* n = take(key);
  if (n == nullptr) fail(key, rule.expected);
  return checked_number(key, *n, rule);
}

double Table::number_or(const std::string& key, double dflt, const NumberRule& rule) {
  const detail::Node* n = take(key);
  return n ? checked_number(key, *n, rule) : dflt;
}

std::optional<double> Table::optional_number(const std::string& key, const NumberRule& rule) {
  const detail::Node* n = take(key);
  return n ? std::optional<double>(checked_number(key, *n, rule)) : std::nullopt;
}

bool Table::boolean(const std::string& key) {
  const detail::Node* n = take(key);
  const auto value = n ? toml_node(*n).value_exact<bool>() : std::nullopt;
  if (!value) fail(key, "true or false");
  return *value;
}

bool Table::boolean_or(const std::string& key, bool dflt) {
  return take(key) ? boolean(key) : dflt;
}

std::string Table::string(const std::string& key, const std::string& expected) {
  const detail::Node* n = take(key);
  const auto value = n ? toml_node(*n).value_exact<std::string>() : std::nullopt;
  if (!value) fail(key, expected);
  return *value;
}

std::string Table::string_or(const std::string& key, const std::string& dflt,
                             const std::string& expected) {
  return take(key) ? string(key, expected) : dflt;
}

std::string Table::choice(const std::string& key, const std::vector<std::string>& options) {
  std::vector<std::string> quoted;
  for (const std::string& option : options)
    quoted.push_back("\"" + option + "\"");
  const std::string expected = join(quoted, " or ");
  const std::string value = string(key, expected);
  if (std::find(options.begin(), options.end(), value) == options.end()) fail(key, expected);
  return value;
}

std::string Table::choice_or(const std::string& key, const std::string& dflt,
                             const std::vector<std::string>& options) {
  return take(key) ? choice(key, options) : dflt;
}

std::vector<double> Table::numbers(const std::string& key, std::size_t min_count,
                                   std::size_t max_count, const std::string& expected) {
  const detail::Node* n = take(key);
  const toml::array* array = n ? toml_node(*n).as_array() : nullptr;
  if (array == nullptr || array->size() < min_count || array->size() > max_count) {
    fail(key, expected);
  }
  std::vector<double> out;
  for (const toml::node& element : *array) {
    const auto value = element.is_number() ? element.value<double>() : std::nullopt;
    if (!value || !std::isfinite(*value)) fail(key, expected);
    out.push_back(*value);
  }
  return out;
}

std::vector<std::string> Table::strings(const std::string& key, std::size_t min_count,
                                        std::size_t max_count, const std::string& expected) {
  const detail::Node* n = take(key);
  const toml::array* array = n ? toml_node(*n).as_array() : nullptr;
  if (array == nullptr || array->size() < min_count || array->size() > max_count) {
    fail(key, expected);
  }
  std::vector<std::string> out;
  for (const toml::node& element : *array) {
    const auto value = element.value<std::string>();
    if (!element.is_string() || !value) fail(key, expected);
    out.push_back(*value);
  }
  return out;
}

std::string Table::resolve(const std::string& written) const {
  const fs::path path(written);
  return (path.is_absolute() ? path : parsed_->folder / path).lexically_normal().string();
}

std::string Table::existing_file(const std::string& key, const std::string& what) {
  const std::string expected = "the path of " + what;
  const std::string written = string(key, expected);
  if (written.empty()) fail(key, expected);
  const std::string path = resolve(written);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    fail(key, expected + " (relative to " + parsed_->what + ")", path + " is not an existing file");
  }
  return path;
}

Table Table::table(const std::string& key) {
  const detail::Node* n = take(key);
  if (toml_table(n) == nullptr) fail(key, "a table [" + field(key) + "]");
  return Table(parsed_, n, field(key));
}

Table Table::optional_table(const std::string& key) {
  return take(key) ? table(key) : Table(parsed_, nullptr, field(key));
}

std::vector<Table> Table::tables(const std::string& key, const std::string& expected) {
  const detail::Node* n = take(key);
  const toml::array* array = n ? toml_node(*n).as_array() : nullptr;
  if (array == nullptr || array->empty()) fail(key, expected);
  std::vector<Table> out;
  for (std::size_t i = 0; i < array->size(); ++i) {
    const toml::node* element = array->get(i);
    if (!element->is_table()) fail(key, expected);
    out.push_back(Table(parsed_, opaque(element), field(key) + "[" + std::to_string(i) + "]"));
  }
  return out;
}

std::map<std::int64_t, std::string> Table::strings_by_code(std::int64_t min, std::int64_t max,
                                                           const std::string& code,
                                                           const std::string& value_expected) {
  std::map<std::int64_t, std::string> out;
  std::map<std::int64_t, std::string> written_as;  // code -> key as written
  const toml::table* table = toml_table(table_);
  if (table == nullptr) return out;
  for (const auto& [name, value] : *table) {
    const std::string key(name.str());
    take(key);
    const std::optional<std::int64_t> c = parse_code(key);
    if (!c || *c < min || *c > max) {
      fail(key, code + " in " + std::to_string(min) + ".." + std::to_string(max) +
                    " as the key, in decimal (177) or hex (0xB1)");
    }
    if (const auto other = written_as.find(*c); other != written_as.end()) {
      fail(key, "each code once",
           "code " + std::to_string(*c) + " is also written as " + field(other->second));
    }
    const auto text = value.value_exact<std::string>();
    if (!text) fail(key, value_expected);
    written_as[*c] = key;
    out[*c] = *text;
  }
  return out;
}

void Table::ignore(const std::string& key) {
  take(key);
}

void Table::reject_unknown(const std::string& expected) const {
  const toml::table* table = toml_table(table_);
  if (table == nullptr) return;
  for (const auto& [name, value] : *table) {
    const std::string key(name.str());
    if (std::find(asked_.begin(), asked_.end(), key) != asked_.end()) continue;
    fail(key,
         !expected.empty() ? expected
         : asked_.empty()  ? "no key in " + (name_.empty() ? std::string("the file") : name_)
                           : "one of " + join(asked_, ", "),
         "unknown key (misspelt?)");
  }
}

std::string Table::to_toml() const {
  const toml::table* table = toml_table(table_);
  if (table == nullptr) return "";
  std::ostringstream text;
  text << *table;
  return text.str() + "\n";
}

}  // namespace config
