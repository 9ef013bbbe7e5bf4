#include "tools/common/preset_option.h"

#include <string_view>
#include <vector>

namespace pnp::tools {

std::string_view value_in_args(int argc, char** argv, std::string_view flag,
                               std::string_view fallback) {
  std::string_view value = fallback;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg == flag && i + 1 < argc) value = argv[i + 1];
    if (arg.size() > flag.size() && arg.starts_with(flag) && arg[flag.size()] == '=')
      value = arg.substr(flag.size() + 1);
  }
  return value;
}

const training::Preset& preset_in_args(int argc, char** argv) {
  const std::string_view name = value_in_args(argc, argv, "--preset", training::kDefaultPreset);
  for (const training::Preset& p : training::presets())
    if (p.name == name) return p;
  return training::find_preset(training::kDefaultPreset, "--preset");
}

void add_preset_options(CLI::App& app, std::string& preset_name, bool& show_preset) {
  std::vector<std::string> names;
  std::string help = "the whole configuration:";
  for (const training::Preset& p : training::presets()) {
    names.emplace_back(p.name);
    help += " " + std::string(p.name) + (p.uses_demonstrations ? " (uses demonstrations)" : "");
    help += p.name == training::kDefaultPreset ? " [default]," : ",";
  }
  help.back() = ';';
  help += " other flags override single values";
  app.add_option("--preset", preset_name, help)->check(CLI::IsMember(names))->capture_default_str();
  app.add_flag("--show-preset", show_preset, "print the preset in full as JSON and exit");
}

}  // namespace pnp::tools
