#pragma once
// Shared plumbing for the command-line tools: run a tool body, turning pnp::Error and
// CLI11 parse errors into one clear line on stderr and a non-zero exit code.

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace pnp::tools {

// Adds --version (common/version.h), parses, runs `body`. Exit codes: 0 success (and
// --help, --version), 2 bad usage or input, 1 any other failure.
int run_tool(CLI::App& app, int argc, char** argv, const std::function<void()>& body);

// Creates `dir` if needed and checks a file can be written in it, before any long work:
// INVALID_ARGUMENT naming `flag` and the reason otherwise (a typo in --out must not cost
// a whole training run).
void require_writable_directory(const std::string& dir, const std::string& flag);

}  // namespace pnp::tools
