#include "rig/estimator/child_process.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <thread>

extern char** environ;

namespace rig::estimator {
namespace {

std::string errno_text(const std::string& what) {
  return what + ": " + std::strerror(errno);
}

// Milliseconds left until `deadline` for poll(2), at least 0, rounded up:
// a deadline less than 1 ms ahead waits 1 ms instead of returning at once.
int poll_ms(ChildProcess::Clock::time_point deadline) {
  const auto left = deadline - ChildProcess::Clock::now();
  if (left <= std::chrono::nanoseconds::zero()) return 0;
  const auto ms = std::chrono::ceil<std::chrono::milliseconds>(left).count();
  return static_cast<int>(std::min<long long>(ms, 1 << 30));
}

// Waits until `fd` is ready for `events` or the deadline passes; false on timeout.
bool wait_ready(int fd, short events, ChildProcess::Clock::time_point deadline) {
  for (;;) {
    pollfd p{fd, events, 0};
    const int n = ::poll(&p, 1, poll_ms(deadline));
    if (n > 0) return true;
    if (n == 0) return false;
    if (errno != EINTR) throw ChildError(errno_text("poll"));
  }
}

std::string describe_status(int status) {
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = strsignal(sig);
    return "killed by signal " + std::to_string(sig) + (name ? std::string(" (") + name + ")" : "");
  }
  return "ended with wait status " + std::to_string(status);
}

}  // namespace

ChildProcess::ChildProcess(const std::vector<std::string>& argv, const std::string& working_dir) {
  if (argv.empty() || argv[0].empty()) throw ChildError("no program to start (empty command)");
  // stdin is a socket pair so that writing to a child that has gone away
  // fails with EPIPE (send MSG_NOSIGNAL) instead of raising SIGPIPE in rig.
  int in[2], out[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, in) == -1)
    throw ChildError(errno_text("socketpair"));
  if (::pipe2(out, O_CLOEXEC) == -1) {
    ::close(in[0]);
    ::close(in[1]);
    throw ChildError(errno_text("pipe2"));
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, in[1], STDIN_FILENO);
  posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
  if (!working_dir.empty()) posix_spawn_file_actions_addchdir_np(&actions, working_dir.c_str());
  // Its own process group: a Ctrl-C meant for rig (which finishes the current
  // position first) does not kill the estimator in the middle of a frame.
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attr, 0);
  std::vector<char*> args;
  for (const std::string& a : argv)
    args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const int rc = ::posix_spawnp(&pid_, args[0], &actions, &attr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  ::close(in[1]);
  ::close(out[1]);
  if (rc != 0) {
    ::close(in[0]);
    ::close(out[0]);
    pid_ = -1;
    throw ChildError("cannot start " + argv[0] + ": " + std::strerror(rc));
  }
  stdin_fd_ = in[0];
  stdout_fd_ = out[0];
  ::fcntl(stdin_fd_, F_SETFL, ::fcntl(stdin_fd_, F_GETFL) | O_NONBLOCK);
  ::fcntl(stdout_fd_, F_SETFL, ::fcntl(stdout_fd_, F_GETFL) | O_NONBLOCK);
}

ChildProcess::~ChildProcess() {
  stop(Clock::now());
  if (stdout_fd_ >= 0) ::close(stdout_fd_);
}

void ChildProcess::write_all(std::string_view bytes, Clock::time_point deadline) {
  if (stdin_fd_ < 0) throw ChildError(ended_or("its stdin is closed"));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n =
        ::send(stdin_fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n >= 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (errno == EINTR) continue;
    if (errno != EAGAIN && errno != EWOULDBLOCK) {
      const std::string why = errno_text("writing to its stdin");
      // It closed its stdin: it has exited or is exiting; say how when it has.
      stop(Clock::now() + std::chrono::milliseconds(200));
      throw ChildError(ended_or(why));
    }
    if (!wait_ready(stdin_fd_, POLLOUT, deadline))
      throw ChildTimeout("it did not read its stdin in time");
  }
}

std::string ChildProcess::read_line(Clock::time_point deadline, std::size_t max_line_bytes) {
  for (;;) {
    const auto newline = buffer_.find('\n');
    if (newline != std::string::npos) {
      std::string line = buffer_.substr(0, newline);
      buffer_.erase(0, newline + 1);
      return line;
    }
    if (buffer_.size() > max_line_bytes)
      throw ChildError("it wrote a line longer than " + std::to_string(max_line_bytes) + " bytes");
    if (stdout_fd_ < 0 || !wait_ready(stdout_fd_, POLLIN, deadline))
      throw ChildTimeout("no whole line on its stdout in time");
    char chunk[65536];
    const ssize_t n = ::read(stdout_fd_, chunk, sizeof chunk);
    if (n > 0) {
      buffer_.append(chunk, static_cast<std::size_t>(n));
      continue;
    }
    if (n == 0) {
      // End of file: the child closed its stdout, which is how it exits.
      // Give it a moment to be reaped so the message can say how it ended.
      stop(Clock::now() + std::chrono::milliseconds(200));
      throw ChildError(ended_or("it closed its stdout"));
    }
    if (errno != EINTR && errno != EAGAIN) throw ChildError(errno_text("reading its stdout"));
  }
}

void ChildProcess::close_stdin() {
  if (stdin_fd_ >= 0) ::close(stdin_fd_);
  stdin_fd_ = -1;
}

void ChildProcess::stop(Clock::time_point deadline) {
  close_stdin();
  while (pid_ > 0 && !exit_description()) {
    if (Clock::now() >= deadline) {
      // The whole process group (the child leads its own): whatever it
      // started goes with it.
      ::kill(-pid_, SIGKILL);
      ::kill(pid_, SIGKILL);
      int status = 0;
      while (::waitpid(pid_, &status, 0) == -1 && errno == EINTR) {
      }
      ended_ = describe_status(status);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

std::optional<std::string> ChildProcess::exit_description() {
  if (ended_ || pid_ <= 0) return ended_;
  int status = 0;
  const pid_t r = ::waitpid(pid_, &status, WNOHANG);
  if (r == pid_) ended_ = describe_status(status);
  return ended_;
}

std::string ChildProcess::ended_or(const std::string& otherwise) {
  const auto ended = exit_description();
  return ended ? "it " + *ended : otherwise;
}

}  // namespace rig::estimator
