#include "browser.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

namespace rig_test {
namespace {

constexpr const char* kChromium = "/usr/bin/chromium";
constexpr auto kRunTimeout = std::chrono::seconds(60);
// After Chromium's main process exits, helpers it forked may still hold the
// pipes; read what is left for this long, then end the process group.
constexpr auto kDrainGrace = std::chrono::seconds(2);

struct ProcessRun {
  bool started = false, timed_out = false;
  int exit_code = -1;  // -1: killed by a signal or not started
  std::string out, err;
};

// Runs argv[0] with argv in its own process group, capturing stdout and
// stderr; kills the group on timeout and once the main process has exited.
ProcessRun run_process(const std::vector<std::string>& argv) {
  ProcessRun run;
  int out_pipe[2], err_pipe[2];
  if (::pipe2(out_pipe, O_CLOEXEC) != 0) return run;
  if (::pipe2(err_pipe, O_CLOEXEC) != 0) {
    ::close(out_pipe[0]);
    ::close(out_pipe[1]);
    return run;
  }
  std::vector<char*> args;
  for (const std::string& a : argv)
    args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setpgid(0, 0);
    ::dup2(out_pipe[1], STDOUT_FILENO);
    ::dup2(err_pipe[1], STDERR_FILENO);
    const int devnull = ::open("/dev/null", O_RDONLY);
    if (devnull >= 0) ::dup2(devnull, STDIN_FILENO);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  if (pid < 0) {
    ::close(out_pipe[0]);
    ::close(err_pipe[0]);
    return run;
  }
  ::setpgid(pid, pid);  // also from here, so the group exists before any kill
  run.started = true;
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + kRunTimeout;
  Clock::time_point drain_until = Clock::time_point::max();
  pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
  std::string* sinks[2] = {&run.out, &run.err};
  bool reaped = false;
  int status = 0;
  for (;;) {
    const bool open_pipes = fds[0].fd >= 0 || fds[1].fd >= 0;
    if (!reaped && ::waitpid(pid, &status, WNOHANG) == pid) {
      reaped = true;
      drain_until = Clock::now() + kDrainGrace;
    }
    if (reaped && (!open_pipes || Clock::now() > drain_until)) break;
    if (!reaped && Clock::now() > deadline) {
      run.timed_out = true;
      ::kill(-pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      reaped = true;
      break;
    }
    if (!open_pipes) {
      ::usleep(20000);
      continue;
    }
    if (::poll(fds, 2, 100) <= 0) continue;
    for (int k = 0; k < 2; ++k) {
      if (fds[k].fd < 0 || !(fds[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      char buf[65536];
      const ssize_t n = ::read(fds[k].fd, buf, sizeof buf);
      if (n > 0) {
        sinks[k]->append(buf, static_cast<size_t>(n));
      } else {
        ::close(fds[k].fd);
        fds[k].fd = -1;
      }
    }
  }
  ::kill(-pid, SIGKILL);  // helpers left behind by the main process, if any
  for (pollfd& p : fds)
    if (p.fd >= 0) ::close(p.fd);
  if (!run.timed_out && WIFEXITED(status)) run.exit_code = WEXITSTATUS(status);
  return run;
}

std::string file_url(const std::string& path) {
  const std::string absolute = std::filesystem::absolute(path).lexically_normal().string();
  std::string url = "file://";
  for (unsigned char c : absolute) {
    if (std::isalnum(c) || c == '/' || c == '-' || c == '_' || c == '.' || c == '~') {
      url += static_cast<char>(c);
    } else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", c);
      url += hex;
    }
  }
  return url;
}

// A new empty profile directory, removed when this goes out of scope.
struct TempProfile {
  std::string path;
  TempProfile() {
    std::string pattern =
        (std::filesystem::temp_directory_path() / "rig_chromium_profile_XXXXXX").string();
    if (::mkdtemp(pattern.data()) != nullptr) path = pattern;
  }
  ~TempProfile() {
    std::error_code ignored;
    if (!path.empty()) std::filesystem::remove_all(path, ignored);
  }
  TempProfile(const TempProfile&) = delete;
  TempProfile& operator=(const TempProfile&) = delete;
};

ProcessRun run_chromium(const std::vector<std::string>& mode_flags, const std::string& url) {
  TempProfile profile;
  std::vector<std::string> argv = {kChromium,
                                   // No network, no sandbox (root), a fresh profile.
                                   "--headless", "--no-sandbox", "--disable-gpu",
                                   "--disable-background-networking", "--disable-component-update",
                                   "--no-first-run", "--user-data-dir=" + profile.path,
                                   // Let load handlers run before the DOM is dumped.
                                   "--virtual-time-budget=5000",
                                   // Console messages on stderr.
                                   "--enable-logging=stderr", "--v=0"};
  argv.insert(argv.end(), mode_flags.begin(), mode_flags.end());
  argv.push_back(url);
  if (profile.path.empty()) return {};
  return run_process(argv);
}

// Console lines look like
//   [3124:3124:1122/072546.050223:INFO:CONSOLE:1] "Uncaught Error: boom", source: file:///p.html
//   (1)
// (older Chromium: "INFO:CONSOLE(1)"). Everything else on stderr is
// Chromium's own log (dbus, gpu, sandbox) and is not the page's doing.
std::vector<std::string> console_messages(const std::string& stderr_text) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start < stderr_text.size()) {
    size_t end = stderr_text.find('\n', start);
    if (end == std::string::npos) end = stderr_text.size();
    const std::string line = stderr_text.substr(start, end - start);
    start = end + 1;
    const size_t tag = line.find(":CONSOLE");
    const size_t close = line.find("] ", tag == std::string::npos ? 0 : tag);
    if (tag == std::string::npos || close == std::string::npos || line[0] != '[') continue;
    out.push_back(line.substr(close + 2));
  }
  return out;
}

int page_height(const std::string& dom) {
  static const std::regex kHeight(R"re(data-page-height="([0-9]+)")re");
  std::smatch m;
  if (!std::regex_search(dom, m, kHeight)) return 2000;
  return std::clamp(std::atoi(m[1].str().c_str()), 600, 16000);
}

}  // namespace

bool chromium_available() {
  return ::access(kChromium, X_OK) == 0;
}

BrowserResult render_in_chromium(const std::string& html_path, const std::string& screenshot_png,
                                 int window_width) {
  BrowserResult result;
  const std::string url = file_url(html_path);
  const std::string width = std::to_string(window_width);
  const ProcessRun dom = run_chromium({"--dump-dom", "--window-size=" + width + ",900"}, url);
  result.dom = dom.out;
  result.stderr_text = dom.err;
  result.console_errors = console_messages(dom.err);
  result.timed_out = dom.timed_out;
  result.ran = dom.started && !dom.timed_out;
  result.exit_code = dom.exit_code;
  if (screenshot_png.empty()) return result;

  std::error_code ignored;
  std::filesystem::remove(screenshot_png, ignored);  // a stale PNG must not pass
  const std::string size = "--window-size=" + width + "," + std::to_string(page_height(dom.out));
  const ProcessRun shot = run_chromium({"--screenshot=" + screenshot_png, size}, url);
  result.stderr_text += shot.err;
  result.timed_out = result.timed_out || shot.timed_out;
  result.ran = result.ran && shot.started && !shot.timed_out;
  if (result.exit_code == 0) result.exit_code = shot.exit_code;
  result.screenshot_written = std::filesystem::exists(screenshot_png, ignored) &&
                              std::filesystem::file_size(screenshot_png, ignored) > 0;
  return result;
}

}  // namespace rig_test
