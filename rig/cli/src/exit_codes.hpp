// The exit codes of rig and the one place that turns a subcommand's errors
// into them. Every subcommand runs its body through run_command:
//   0  success
//   1  a failure while running: hardware, I/O, a peer that does not answer
//   2  bad input: a file, option or value that cannot be used; the message
//      names the input, the value and what was expected
//   3  `rig report --fail-on-regression`: written, and a solver got worse
// An error is printed on stderr as "rig COMMAND: message", or
// "rig COMMAND: SUBJECT: message" where SUBJECT names the part of the rig
// that failed (camera, bench, database, telemetry) and the command is not
// named after it.
#pragma once

#include <functional>
#include <stdexcept>
#include <string>

namespace rig::cli {

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitRegression = 3;

// Bad input a subcommand finds itself (options that contradict each other, a
// problem file's key); exit 2.
class BadInput : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Runs `body`, which returns the exit code, for `rig COMMAND`. An exception it
// throws is printed as above and gives the code of its type: the first row
// of the table in exit_codes.cpp that the exception is an instance of; any
// other std::exception is a failure while running (1). Returns the code.
int run_command(const std::string& command, const std::function<int()>& body);

// Reads or checks an input of a command: whatever `read` throws is bad input
// (BadInput "INPUT: message", or the message alone when `input` is empty),
// even an error type that is otherwise a failure while running
// (vision::ArtworkError is both an unknown file extension and a file that
// cannot be written).
void read_input(const std::string& input, const std::function<void()>& read);

}  // namespace rig::cli
