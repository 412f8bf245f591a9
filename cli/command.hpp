#pragma once
// Subcommands of the `sextant` tool register themselves, one per file in cli/, so adding a command
// touches no shared file.  A command reports failure by throwing CLI::RuntimeError(exit_code) (or any
// std::exception, which main turns into exit code 1 with its message).
#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace sextant::cli {

struct Command {
  std::string name;                        // subcommand name, for ordering the help text
  std::function<void(CLI::App& app)> add;  // adds the subcommand, its options and its callback to `app`
};

std::vector<Command>& command_registry();

struct RegisterCommand {
  RegisterCommand(std::string name, std::function<void(CLI::App&)> add) {
    command_registry().push_back({std::move(name), std::move(add)});
  }
};

}  // namespace sextant::cli
