// Renders a page in headless Chromium (Debian's `chromium`) for the report
// tests: the DOM after the page's scripts ran, the page's console messages,
// and a screenshot for a person to look at.
#pragma once

#include <string>
#include <vector>

namespace rig_test {

struct BrowserResult {
  bool ran = false;        // both Chromium runs started and exited by themselves (no timeout)
  int exit_code = -1;      // the first non-zero exit status of the two runs, else 0; -1 if killed
  bool timed_out = false;  // a run was killed after 60 s
  std::string dom;         // document.documentElement.outerHTML after load (--dump-dom)
  // Every console message of the page (from the --dump-dom run), e.g.
  // `"Uncaught Error: boom", source: file:///tmp/p.html (3)`. Chromium logs
  // console.log and console.error alike as "INFO:CONSOLE", so the level is
  // not known: every message counts, and a page under test must not log.
  // Uncaught exceptions, refused loads (Content-Security-Policy) and missing
  // resources all appear here.
  std::vector<std::string> console_errors;
  std::string stderr_text;          // both runs' standard error, for diagnostics
  bool screenshot_written = false;  // the PNG exists and is not empty
};

// Runs /usr/bin/chromium twice on file://<absolute html_path>, each time with
// exactly these flags (--headless --no-sandbox --disable-gpu
// --disable-background-networking --disable-component-update --no-first-run),
// a new empty --user-data-dir (removed after), --virtual-time-budget=5000 so
// load handlers run, and --enable-logging=stderr --v=0 for the console:
//   1. --dump-dom --window-size=<window_width>,900: fills `dom` and `console_errors`;
//   2. --screenshot=<screenshot_png> --window-size=<window_width>,<h>, h the page height
//      the page reported in <body data-page-height> (see db/html_page.hpp),
//      else 2000 px, clamped to [600, 16000].
// Each run is killed (with its process group) after 60 s. Chromium's own log
// lines (dbus, gpu, ...) are ignored: only console lines are collected.
// screenshot_png "" skips the second run.
// window_width: the CSS width of both runs' window (the first run's is
// window_width x 900).
BrowserResult render_in_chromium(const std::string& html_path, const std::string& screenshot_png,
                                 int window_width = 1280);

// /usr/bin/chromium exists and is executable.
bool chromium_available();

}  // namespace rig_test
