// SPDX-License-Identifier: MIT
// Command-line parsing shared by the benchmark programs: --help prints the
// usage and exits 0; a bad option or value prints one line naming it, with
// exit status 2 (as bspc and walkers do).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

namespace bspf::bench {

/// Parses the command line into `app`. Returns -1 when the program should go
/// on, else the status to exit with (0 after --help, 2 for a bad command
/// line, whose error it has printed as "NAME: error: ... (see NAME --help)").
inline int parseCommandLine(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
    return -1;
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    const std::string name = app.get_name();
    std::fprintf(stderr, "%s: error: %s (see %s --help)\n", name.c_str(), e.what(), name.c_str());
    return 2;
  }
}

}  // namespace bspf::bench
