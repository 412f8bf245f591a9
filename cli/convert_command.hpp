#pragma once
// What the `sextant convert` formats share (cli/convert.cpp: data sets into LCM logs; cli/convert_mcap.cpp: LCM logs
// and MCAP files): the one `convert` subcommand they add their formats to, and how a format's failure is reported.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

namespace sextant::cli {

/// The `convert` subcommand of `app`, made by whichever format registers first.
inline CLI::App* convert_command(CLI::App& app) {
  for (auto* c : app.get_subcommands([](CLI::App* s) { return s->get_name() == "convert"; })) return c;
  auto* c = app.add_subcommand("convert", "convert data sets into LCM logs, and LCM logs to and from MCAP files");
  c->require_subcommand(1);
  return c;
}

/// Runs the conversion `f` of format `what`; what it throws is printed as "sextant convert WHAT: ..." and exits 2.
template <class F>
void convert_guarded(const char* what, F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sextant convert %s: %s\n", what, e.what());
    throw CLI::RuntimeError(2);
  }
}

}  // namespace sextant::cli
