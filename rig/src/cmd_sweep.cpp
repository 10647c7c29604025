// rig sweep: placeholder while it is being written this session.
#include <iostream>

#include "commands.hpp"

namespace rig {

void add_sweep_command(CLI::App& app, ExitStatus& status) {
  auto* cmd = app.add_subcommand("sweep", "(being written)");
  cmd->allow_extras();
  cmd->callback([&status] {
    std::cerr << "rig sweep: not built yet\n";
    status.code = kExitFailure;
  });
}

}  // namespace rig
