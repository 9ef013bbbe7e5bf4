#pragma once
// Shared plumbing for the command-line tools: run a tool body, turning pnp::Error and
// CLI11 parse errors into one clear line on stderr and a non-zero exit code.

#include <CLI/CLI.hpp>
#include <functional>

namespace pnp::tools {

// Exit codes: 0 success, 2 bad usage or input, 1 any other failure.
int run_tool(CLI::App& app, int argc, char** argv, const std::function<void()>& body);

}  // namespace pnp::tools
