#include "config/json.hpp"

namespace config {
namespace {

// Thrown from the parser callback to stop at the first level too deep.
struct TooDeep {};

}  // namespace

nlohmann::json parse_json(std::string_view text, const std::string& input,
                          const JsonLimits& limits) {
  if (text.size() > limits.max_bytes)
    throw JsonInputError(input + ": is " + std::to_string(text.size()) +
                         " bytes long; expected at most " + std::to_string(limits.max_bytes));
  // The callback sees the depth of the value that starts: the outermost
  // array or object starts at depth 0, so it refuses at max_depth.
  const nlohmann::json::parser_callback_t bound =
      [&limits](int depth, nlohmann::json::parse_event_t event, nlohmann::json&) {
        if ((event == nlohmann::json::parse_event_t::object_start ||
             event == nlohmann::json::parse_event_t::array_start) &&
            static_cast<std::size_t>(depth) >= limits.max_depth)
          throw TooDeep{};
        return true;
      };
  try {
    return nlohmann::json::parse(text.begin(), text.end(), bound);
  } catch (const TooDeep&) {
    throw JsonInputError(input + ": nests arrays or objects more than " +
                         std::to_string(limits.max_depth) + " levels deep; expected at most " +
                         std::to_string(limits.max_depth));
  } catch (const nlohmann::json::parse_error& e) {
    throw JsonInputError(input + ": is not valid JSON: " + e.what());
  } catch (const nlohmann::json::exception& e) {
    // out_of_range.406: a number beyond the range of a double.
    throw JsonInputError(input + ": holds a value JSON cannot represent: " + e.what() +
                         "; expected finite numbers");
  }
}

std::string excerpt(std::string_view text, std::size_t max_chars) {
  std::string out(text.substr(0, max_chars));
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20) c = '?';
  if (text.size() > max_chars) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

std::string excerpt_json(const nlohmann::json& value, std::size_t max_chars) {
  return excerpt(
      std::string_view(value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)),
      max_chars);
}

}  // namespace config
