#include "services/common/cli_suggestion.h"

#include <algorithm>
#include <cctype>

namespace pnp::services {
namespace {

// The flags and subcommand names a user could have meant: the app's and, for each
// subcommand on the command line, that subcommand's.
void collect_names(const CLI::App& app, std::vector<std::string>& names) {
  for (const CLI::Option* option : app.get_options()) {
    for (const auto& name : option->get_lnames()) names.push_back("--" + name);
    for (const auto& name : option->get_snames()) names.push_back("-" + name);
  }
  for (const CLI::App* sub : app.get_subcommands({})) {
    names.push_back(sub->get_name());
    if (sub->parsed() > 0) collect_names(*sub, names);
  }
}

bool known(const std::vector<std::string>& names, const std::string& word) {
  return std::find(names.begin(), names.end(), word) != names.end();
}

}  // namespace

std::size_t edit_distance(const std::string& a, const std::string& b) {
  // Optimal string alignment: a swap of two neighbours ("trian") costs one.
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

std::string suggest_for_unknown(const CLI::App& app, const std::vector<std::string>& args) {
  std::vector<std::string> names;
  collect_names(app, names);
  std::string out;
  for (const std::string& arg : args) {
    const std::string word = arg.substr(0, arg.find('='));
    if (word.empty() || known(names, word)) continue;
    const bool flag = word.front() == '-';
    // A value ("3", "127.0.0.1:1") is no misspelt command.
    if (!flag && !std::all_of(word.begin(), word.end(), [](char c) {
          return std::isalpha(static_cast<unsigned char>(c)) != 0;
        }))
      continue;
    std::string best;
    std::size_t best_distance = std::max<std::size_t>(1, word.size() / 3) + 1;
    for (const std::string& name : names) {
      if ((name.front() == '-') != flag) continue;  // a flag for a flag, a command for a command
      const std::size_t d = edit_distance(word, name);
      if (d < best_distance) {
        best_distance = d;
        best = name;
      }
    }
    if (!best.empty()) out += " (" + word + ": did you mean " + best + "?)";
  }
  return out;
}

}  // namespace pnp::services
