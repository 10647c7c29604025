// Runs the `rig` program of this build as a user would, for the CLI tests.
#pragma once

#include <string>

namespace rig_test {

struct RigRun {
  int exit_code = -1;  // the process's exit status; -1 if it did not exit normally
  std::string out;     // standard output
  std::string err;     // standard error
};

// Runs `<build>/bin/rig ARGS` through the shell with `stdin_text` on its
// standard input; stdout and stderr are captured apart.
RigRun run_rig(const std::string& args, const std::string& stdin_text = "");

}  // namespace rig_test
