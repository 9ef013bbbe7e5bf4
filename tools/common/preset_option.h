#pragma once
// --preset and --show-preset for the training tools. A preset sets the defaults of every
// other option, so it is read from the command line before the options are declared
// (their defaults, and --help, then show the preset's values); flags given with it
// override single values.

#include <CLI/CLI.hpp>
#include <string>

#include "training/preset.h"

namespace pnp::tools {

// The value of `flag` in argv (FLAG VALUE or FLAG=VALUE; the last one wins), or
// `fallback`: for options whose value sets other options' defaults.
std::string_view value_in_args(int argc, char** argv, std::string_view flag,
                               std::string_view fallback);

// The preset named by --preset in argv (--preset NAME or --preset=NAME), or the default
// one. An unknown name gives the default here: the option's own check then refuses it
// when the command line is parsed.
const training::Preset& preset_in_args(int argc, char** argv);

// Declares --preset (checked against the preset names) and --show-preset (print the
// preset in full as JSON and exit) on `app`.
void add_preset_options(CLI::App& app, std::string& preset_name, bool& show_preset);

}  // namespace pnp::tools
