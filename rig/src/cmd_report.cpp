// rig report: placeholder while it is being written this session.
#include <iostream>

#include "commands.hpp"

namespace rig {

void add_report_command(CLI::App& app, ExitStatus& status) {
  auto* cmd = app.add_subcommand("report", "(being written)");
  cmd->allow_extras();
  cmd->callback([&status] {
    std::cerr << "rig report: not built yet\n";
    status.code = kExitFailure;
  });
}

}  // namespace rig
