// `rig monitor` in a real terminal: a detached tmux session of 80 x 24
// characters runs the monitor against a real `rig sweep` on the simulated
// rig, and the pane's text (`tmux capture-pane`) is checked through the whole
// sweep, as a user at an 80 x 24 terminal would see it.
#include <gtest/gtest.h>

#include <chrono>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "sim_rig_fixture.hpp"

namespace {

using namespace std::chrono_literals;
using rig_test::ChildProcess;
using rig_test::SimRig;
using rig_test::SweepFileOptions;

constexpr int kColumns = 80;
constexpr int kRows = 24;
// The fixture's plan: x 300..800 mm in 100 mm steps on one row.
constexpr int kPositions = 6;
// Upper bound on one position of the simulated rig (a 100 mm move at 4x,
// settling, 2 rendered frames, every solver): measured well under 2 s on two
// shared cores; 20 s only bounds a broken test, never a healthy run.
constexpr auto kSlowestPosition = 20s;
// Starting the programs and the first subscription: tens of milliseconds.
constexpr auto kStartup = 30s;
constexpr auto kSweepDeadline = kStartup + kPositions * kSlowestPosition;
// Between two captures: often enough to see every position (each takes
// hundreds of milliseconds), no fixed wait the test's verdict depends on.
constexpr auto kCaptureInterval = 50ms;

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s)
    q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// A tmux server of its own (a socket named after this process), so the test
// neither sees nor disturbs a user's tmux sessions. Killed when it goes away.
class Tmux {
 public:
  Tmux() : socket_("rig-monitor-test-" + std::to_string(::getpid())) {}
  ~Tmux() { run("kill-server 2>/dev/null"); }
  Tmux(const Tmux&) = delete;
  Tmux& operator=(const Tmux&) = delete;

  // tmux ARGS; returns its stdout, *status its exit status.
  std::string run(const std::string& args, int* status = nullptr) const {
    int s = 0;
    const std::string out =
        rig_test::run_command("tmux -L " + socket_ + " -f /dev/null " + args, &s);
    if (status) *status = s;
    return out;
  }

  // A detached session `name` of kColumns x kRows running `command`; the pane
  // stays open after the command (its exit status printed below the last
  // screen, without a newline: one on the last row would scroll the screen),
  // so that the final screen can be captured.
  void start(const std::string& name, const std::string& command) const {
    const std::string script =
        command + "; printf \"monitor exit status %s\" $?; exec cat >/dev/null";
    int status = 0;
    const std::string out =
        run("new-session -d -s " + name + " -x " + std::to_string(kColumns) + " -y " +
                std::to_string(kRows) + " " + shell_quote("sh -c " + shell_quote(script)) + " 2>&1",
            &status);
    ASSERT_EQ(status, 0) << "tmux new-session failed (is tmux installed? scripts/setup): " << out;
  }

  // The pane's screen, wrapped lines joined (-J), so that a line longer than
  // the terminal shows as one long line instead of two short ones.
  std::vector<std::string> capture(const std::string& name) const {
    std::vector<std::string> lines;
    std::istringstream in(run("capture-pane -p -J -t " + name));
    for (std::string line; std::getline(in, line);)
      lines.push_back(line);
    return lines;
  }

 private:
  std::string socket_;
};

// Characters (UTF-8 code points) of a line as the terminal shows them.
std::size_t columns_of(const std::string& line) {
  std::size_t n = 0;
  for (unsigned char c : line)
    n += (c & 0xC0) != 0x80;
  return n;
}

std::string screen_text(const std::vector<std::string>& screen) {
  std::string s;
  for (const auto& line : screen)
    s += line + "\n";
  return s;
}

bool has_line(const std::vector<std::string>& screen, const std::regex& pattern) {
  for (const auto& line : screen)
    if (std::regex_search(line, pattern)) return true;
  return false;
}

// Whether the program in the pane has drawn anything yet.
bool drawn(const std::vector<std::string>& screen) {
  for (const auto& line : screen)
    if (!line.empty()) return true;
  return false;
}

// The progress line: bar, percentage, completed/plan and the ETA.
const std::regex kProgressLine(R"(^\[[#-]{10,}\] +[0-9]+\.[0-9]%  [0-9]+/[0-9?]+  ETA \S+)");

// Every screen of a healthy run: nothing wider than the terminal, no more
// lines than it has, the progress bar and ETA on screen.
void expect_fits(const std::vector<std::string>& screen) {
  EXPECT_LE(screen.size(), static_cast<std::size_t>(kRows)) << screen_text(screen);
  for (const auto& line : screen)
    EXPECT_LE(columns_of(line), static_cast<std::size_t>(kColumns)) << "\"" << line << "\"";
  EXPECT_TRUE(has_line(screen, kProgressLine)) << "no progress line:\n" << screen_text(screen);
}

// Starts `rig sweep`, waiting for one telemetry subscriber (the monitor), and
// returns its endpoints line's telemetry endpoint.
std::string start_sweep(const std::string& sweep, std::unique_ptr<ChildProcess>& child) {
  child = std::make_unique<ChildProcess>(
      std::vector<std::string>{rig_test::rig_binary(), "sweep", sweep, "--no-progress",
                               "--wait-subscribers", "1", "--wait-subscribers-s", "120"});
  static const std::regex kEndpoint(R"(telemetry (tcp://[^,\s]+))");
  const auto deadline = std::chrono::steady_clock::now() + kStartup;
  while (std::chrono::steady_clock::now() < deadline && !child->at_eof()) {
    const auto line = child->read_line(200ms);
    std::smatch m;
    if (line && std::regex_search(*line, m, kEndpoint)) return m[1];
  }
  return "";
}

std::string monitor_command(const std::string& endpoint) {
  return shell_quote(rig_test::rig_binary()) + " monitor --until-stop --timeout-s 120 --endpoint " +
         endpoint;
}

// Completed positions the screen's progress line shows, -1 if none.
int completed_on(const std::vector<std::string>& screen) {
  static const std::regex kCompleted(R"(%  ([0-9]+)/)");
  for (const auto& line : screen) {
    std::smatch m;
    if (std::regex_search(line, m, kCompleted)) return std::stoi(m[1]);
  }
  return -1;
}

TEST(RigMonitorTmux, FitsAn80By24TerminalThroughAWholeSweepAndALateMonitorNamesTheRun) {
  SimRig rig;
  const std::string sweep = rig.write_sweep(SweepFileOptions{});
  std::unique_ptr<ChildProcess> child;
  const std::string endpoint = start_sweep(sweep, child);
  ASSERT_FALSE(endpoint.empty()) << "the sweep did not announce its telemetry endpoint";
  Tmux tmux;
  tmux.start("first", monitor_command(endpoint));

  // The monitor's first screen (before it, the pane is blank: the process is
  // starting); from then on every capture must fit.
  const auto startup_deadline = std::chrono::steady_clock::now() + kStartup;
  while (!drawn(tmux.capture("first"))) {
    ASSERT_LT(std::chrono::steady_clock::now(), startup_deadline) << "rig monitor drew nothing";
    std::this_thread::sleep_for(kCaptureInterval);
  }
  const auto deadline = std::chrono::steady_clock::now() + kSweepDeadline;
  bool late_started = false, late_named_the_run = false;
  int captures = 0, last_completed = -1, progress_steps = 0;
  std::vector<std::string> screen;
  for (;;) {
    ASSERT_LT(std::chrono::steady_clock::now(), deadline)
        << "the sweep did not end within its deadline; last screen:\n"
        << screen_text(screen);
    screen = tmux.capture("first");
    if (has_line(screen, std::regex("^monitor exit status"))) break;
    ++captures;
    expect_fits(screen);
    const int completed = completed_on(screen);
    if (completed > last_completed) {
      ++progress_steps;
      last_completed = completed;
    }
    // A second monitor joins once two positions are stored: it never saw
    // run_start, and must still say which run and database it is showing.
    if (!late_started && completed >= 2) {
      tmux.start("late", monitor_command(endpoint));
      late_started = true;
    }
    if (late_started && !late_named_the_run) {
      const auto late = tmux.capture("late");
      if (drawn(late)) expect_fits(late);
      const std::string head = "run 1 (joined after its start)  ->  " + rig.database();
      late_named_the_run = !late.empty() && late[0].rfind(head, 0) == 0;
    }
    std::this_thread::sleep_for(kCaptureInterval);
  }
  // The final screen: the whole plan done, the run's end, the monitor's exit.
  const std::vector<std::string> last(screen.begin(), screen.end() - 1);
  expect_fits(last);
  EXPECT_TRUE(has_line(screen, std::regex("^monitor exit status 0$"))) << screen_text(screen);
  EXPECT_TRUE(has_line(last, std::regex("100\\.0%  6/6  ETA 0s  failed 0  completed")))
      << screen_text(screen);
  EXPECT_TRUE(has_line(last, std::regex("^last: run 1 completed: 6 ok, 0 failed of 6 positions")))
      << screen_text(screen);
  EXPECT_TRUE(has_line(last, std::regex("^run 1 .*  ->  "))) << screen_text(screen);
  // Seen mid-run, not only at its end.
  EXPECT_GE(captures, 3);
  EXPECT_GE(progress_steps, 2);
  EXPECT_TRUE(late_started);
  EXPECT_TRUE(late_named_the_run) << screen_text(tmux.capture("late"));
  const auto status = child->signal_and_wait(
      0, std::chrono::duration_cast<std::chrono::milliseconds>(kSlowestPosition));
  EXPECT_EQ(status, std::optional<int>(0));
}

}  // namespace
