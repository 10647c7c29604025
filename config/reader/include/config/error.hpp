// config::ConfigError: the one base of every error about a configuration file,
// and the mechanism by which the one reader (config/reader.hpp) throws each
// module's own error type.
#pragma once

#include <stdexcept>
#include <string>
#include <type_traits>

namespace config {

// A configuration file that cannot be used: unreadable, not TOML, a key that
// is missing, unknown, mistyped or out of range, or settings inconsistent with
// each other. It is bad input, never a failure while running: one
// `catch (const config::ConfigError&)` catches a bad drive profile
// (motion::ProfileError), target layout (vision::TargetError), rig file
// (vision::RigConfigError), sweep file (rig::sweep::SweepConfigError) or
// simulated rig file (sim::camera::SimRigConfigError) alike.
//
// Every message has one form (config::error_message):
//   FILE: TABLE.KEY = VALUE: [PROBLEM; ]expected WHAT
// e.g. "ci.toml: capture.frames_per_position = 0: expected an integer in 1..1000".
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// How a reader reports an error: a function that throws the module's error
// type with the complete message. A reader (config::Document and the
// config::Tables it hands out, config::read_text_file) is given one when the
// file is read and calls it for every error it finds, so that the drive
// profile's errors stay motion::ProfileError and a sweep file's stay
// rig::sweep::SweepConfigError while the checks and messages are the same
// code. raise_as<Error> is the Raise of a type; a Raise that returns is
// treated as a bug and the reader throws a plain ConfigError instead.
using Raise = void (*)(const std::string& message);

// The Raise that throws Error(message). Error derives from ConfigError.
template <typename Error>
[[noreturn]] void raise_as(const std::string& message) {
  static_assert(std::is_base_of_v<ConfigError, Error>,
                "a configuration error type derives from config::ConfigError");
  throw Error(message);
}

}  // namespace config
