// sextant: offline and debugging tools around the sextant engine (the README lists the subcommands and their options).
#include "daemon/runtime/version.hpp"
#include "cli/command.hpp"

#include <algorithm>
#include <cstdio>
#include <exception>

namespace sextant::cli {
std::vector<Command>& command_registry() {
  static std::vector<Command> registry;
  return registry;
}
}  // namespace sextant::cli

int main(int argc, char** argv) {
  CLI::App app{"sextant — state estimation over LCM: optimize, replay, simulate, convert, evaluate"};
  app.set_version_flag("--version", sextant::version());
  app.require_subcommand(1);
  auto& registry = sextant::cli::command_registry();
  std::sort(registry.begin(), registry.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  for (const auto& c : registry) c.add(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sextant: %s\n", e.what());
    return 1;
  }
  return 0;
}
