// The one way rig parses JSON that comes from outside the process (a problem
// file, a control request, telemetry, a database's stored descriptions):
// bounded in size and nesting depth, so that no input can exhaust the stack
// (nlohmann's dump() and comparison recurse once per level) or the memory,
// and with excerpts of bounded length for error messages.
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <string_view>

namespace config {

// Bounds of one JSON text. Every JSON rig reads is written by rig or by hand:
// none nests deeper than 10 levels or is near the size bound.
struct JsonLimits {
  std::size_t max_depth = 64;         // nested arrays and objects, the outermost is level 1
  std::size_t max_bytes = 16u << 20;  // 16 MiB
};

// JSON text that cannot be used: longer than max_bytes, not JSON (the message
// has the parser's byte position), a number out of the range of a double, or
// nested deeper than max_depth. The message starts with the input's name.
class JsonInputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Parses `text`, named `input` in errors ("problem 'p.json'", "control
// request"). Throws JsonInputError "INPUT: PROBLEM; expected WHAT". The
// result nests at most limits.max_depth levels deep, so dumping it is safe.
nlohmann::json parse_json(std::string_view text, const std::string& input,
                          const JsonLimits& limits = {});

// At most `max_chars` characters of `text` for an error message, with
// "... (N bytes)" when it was cut; control characters become '?'.
std::string excerpt(std::string_view text, std::size_t max_chars = 80);

// excerpt() of the compact dump of `value`, which must nest at most
// JsonLimits{}.max_depth levels (true of everything parse_json returns).
std::string excerpt_json(const nlohmann::json& value, std::size_t max_chars = 80);

}  // namespace config
