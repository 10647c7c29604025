// rig::estimator::ChildProcess: one external estimator process, started with
// posix_spawnp (no shell: argv[0] is looked up on PATH, every argument is
// passed as written), its stdin (a socket pair) and stdout (a pipe)
// connected to rig,
// its stderr inherited (an estimator's own messages go where rig's go), in a
// process group of its own.
//
// Every wait is bounded by a deadline (poll(2)); nothing here blocks for
// longer than the caller allows, whatever the child does. The destructor
// kills (SIGKILL) and reaps a child that is still running, with its group.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rig::estimator {

// The child cannot be talked to: it could not be started, it closed its end
// of a pipe, it wrote a line longer than allowed, or a system call failed.
// what() says which, and how the child ended when it did.
class ChildError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The deadline passed before the child answered.
class ChildTimeout : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ChildProcess {
 public:
  using Clock = std::chrono::steady_clock;

  // Starts argv (at least one element) in the folder `working_dir` ("" =
  // rig's own working folder; a relative argv[0] containing '/' is then
  // relative to it). Throws ChildError when the pipes or
  // the fork fail; a program that cannot be executed (not found, not
  // executable) makes the child exit with status 127, which the first read
  // or write reports.
  explicit ChildProcess(const std::vector<std::string>& argv, const std::string& working_dir = "");
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }

  // Writes all of `bytes` to the child's stdin before `deadline`. Throws
  // ChildTimeout when the child does not take them in time (its stdin pipe
  // stays full), ChildError when it closed its stdin or exited.
  void write_all(std::string_view bytes, Clock::time_point deadline);

  // The next line the child writes to stdout, without its '\n', read before
  // `deadline`. Throws ChildTimeout when no whole line arrived in time,
  // ChildError when the child closed its stdout (exited) first, or when the
  // line grows beyond max_line_bytes.
  std::string read_line(Clock::time_point deadline, std::size_t max_line_bytes);

  // Closes the child's stdin (it sees end of file), waits until `deadline`
  // for it to exit, then kills it and its process group (SIGKILL) and reaps
  // it. Idempotent.
  void stop(Clock::time_point deadline);

  // How the child ended, when it has ended (reaped without blocking):
  // "exited with status 3", "killed by signal 11 (Segmentation fault)";
  // nothing while it runs.
  std::optional<std::string> exit_description();

 private:
  void close_stdin();
  std::string ended_or(const std::string& otherwise);

  pid_t pid_ = -1;
  int stdin_fd_ = -1;
  int stdout_fd_ = -1;
  std::string buffer_;  // bytes read from stdout after the last whole line
  std::optional<std::string> ended_;
};

}  // namespace rig::estimator
