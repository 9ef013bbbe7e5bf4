#pragma once
// Which code a binary is: the release (the project's version in CMakeLists.txt, as
// CHANGELOG.md names it) and the commit it was built from, "-dirty" when the tree had
// uncommitted changes. Every program answers --version with it, so a result, a log or a
// bug report names the code that produced it.

#include <CLI/CLI.hpp>
#include <string>
#include <string_view>

namespace pnp {

std::string_view release_version();  // "0.1.0"
std::string_view build_commit();     // "1a2b3c4d5e6f", "1a2b3c4d5e6f-dirty" or "unknown"

// "pnp-train 0.1.0 (commit 1a2b3c4d5e6f)"
std::string version_text(std::string_view program);

// Adds --version to a command line: prints version_text(the app's name) and exits 0.
void add_version_flag(CLI::App& app);

}  // namespace pnp
