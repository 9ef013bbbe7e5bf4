#pragma once
// "did you mean --seed?" for a mistyped flag or subcommand: CLI11 says only that an
// argument was not expected. The closest name the parsed command (or its subcommands)
// knows, by edit distance, if close enough to be the one meant.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace pnp::services {

// Edit distance: insertions, deletions, substitutions and swaps of neighbours, one each.
std::size_t edit_distance(const std::string& a, const std::string& b);

// For each argument of `args` that `app` (as far as it parsed) does not know, " (did you
// mean X?)" naming the closest known flag or subcommand; empty if none is close.
std::string suggest_for_unknown(const CLI::App& app, const std::vector<std::string>& args);

}  // namespace pnp::services
