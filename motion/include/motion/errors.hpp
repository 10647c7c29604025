// The typed errors of the motion module. Each is thrown at the boundary where
// its cause is known, with a message naming the input, the value and what was
// expected. A sweep catches BenchError and never records a position after one.
#pragma once

#include <stdexcept>
#include <string>

#include "config/error.hpp"

namespace motion {

// A drive profile (or bench URL) that is missing a field, has a field of the
// wrong type or value, or is inconsistent (overlapping registers, duplicate
// status bits or command codes, empty soft limits). Bad input, found before
// anything is sent to a bench: a config::ConfigError, not a BenchError. A
// profile's message has the form of every configuration file
// (config/error.hpp), e.g.
//   "sim.toml: registers.target_y = 1: registers 1..2 overlap registers.target_x
//    (0..1); expected registers that no other field of the same table uses";
// a bench URL's names the URL: "bench URL tcp://h:1: expected modbus-tcp://...".
class ProfileError : public config::ConfigError {
 public:
  using config::ConfigError::ConfigError;
};

// Base of every bench error.
class BenchError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A move refused before anything was sent: the target lies outside the soft
// limits of the profile, or is not a finite number.
class SoftLimitError : public BenchError {
 public:
  using BenchError::BenchError;
};

// The drive reports an alarm or an emergency stop. code() is the drive's alarm
// code (0 for an emergency stop without a code), meaning() its text from the
// profile's [alarms] table.
class BenchFault : public BenchError {
 public:
  BenchFault(const std::string& what, int code, std::string meaning)
      : BenchError(what), code_(code), meaning_(std::move(meaning)) {}
  int code() const { return code_; }
  const std::string& meaning() const { return meaning_; }

 private:
  int code_;
  std::string meaning_;
};

// A write the drive refused (Modbus exception response) or that did not read
// back as written. Nothing after it was sent.
class BenchWriteError : public BenchError {
 public:
  using BenchError::BenchError;
};

// wait_settled ran out of time before the bench was settled.
class BenchTimeout : public BenchError {
 public:
  using BenchError::BenchError;
};

// The link to the drive is down and could not be re-established within the
// profile's reconnect timeout, or it came back with a bench whose state no
// longer matches what was commanded (a drive restarted: not homed any more,
// targets cleared). The bench must be re-homed or inspected by a person.
class BenchLinkError : public BenchError {
 public:
  using BenchError::BenchError;
};

}  // namespace motion
