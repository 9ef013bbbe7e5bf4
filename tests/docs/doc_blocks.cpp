#include "tests/docs/doc_blocks.h"

#include <sstream>
#include <string_view>

namespace pnp::docs {
namespace {

constexpr std::string_view kOpen = "<!-- docs-test:";
constexpr std::string_view kClose = "-->";

std::string trim(std::string_view text) {
  const auto begin = text.find_first_not_of(" \t");
  if (begin == std::string_view::npos) return {};
  const auto end = text.find_last_not_of(" \t\r");
  return std::string(text.substr(begin, end - begin + 1));
}

bool starts_with(std::string_view text, std::string_view prefix) {
  return text.substr(0, prefix.size()) == prefix;
}

BlockPlan malformed(std::string why) {
  BlockPlan plan;
  plan.kind = BlockPlan::Kind::kMalformed;
  plan.reason = std::move(why);
  return plan;
}

// "run" followed by "; ci: A => B" clauses.
BlockPlan parse_run(std::string_view body) {
  BlockPlan plan;
  plan.kind = BlockPlan::Kind::kRun;
  std::size_t at = body.find(';');
  if (trim(body.substr(0, at)) != "run") return malformed("expected \"run\" or \"skip: REASON\"");
  while (at != std::string_view::npos) {
    const std::size_t next = body.find(';', at + 1);
    const std::string clause = trim(body.substr(at + 1, next - at - 1));
    if (!starts_with(clause, "ci:"))
      return malformed("expected \"ci: FROM => TO\", got \"" + clause + "\"");
    const std::string rule = clause.substr(3);
    const std::size_t arrow = rule.find("=>");
    if (arrow == std::string::npos)
      return malformed("expected \"ci: FROM => TO\", got \"" + clause + "\"");
    Substitution s{trim(rule.substr(0, arrow)), trim(rule.substr(arrow + 2))};
    if (s.from.empty()) return malformed("a ci: substitution needs text to replace");
    plan.substitutions.push_back(std::move(s));
    at = next;
  }
  return plan;
}

bool is_shell(const std::string& language) {
  return language == "sh" || language == "bash" || language == "shell";
}

}  // namespace

BlockPlan parse_marker(const std::string& line) {
  const std::string text = trim(line);
  if (!starts_with(text, kOpen)) return {};
  if (text.size() < kOpen.size() + kClose.size() ||
      text.substr(text.size() - kClose.size()) != kClose)
    return malformed("a marker is one line ending in \"-->\"");
  const std::string body =
      trim(std::string_view(text).substr(kOpen.size(), text.size() - kOpen.size() - kClose.size()));
  if (starts_with(body, "skip")) {
    const std::size_t colon = body.find(':');
    const std::string reason = colon == std::string::npos ? "" : trim(body.substr(colon + 1));
    if (trim(body.substr(0, colon)) != "skip" || reason.empty())
      return malformed("a skipped block says why: \"skip: REASON\"");
    BlockPlan plan;
    plan.kind = BlockPlan::Kind::kSkip;
    plan.reason = reason;
    return plan;
  }
  return parse_run(body);
}

std::vector<ShellBlock> shell_blocks(const std::string& markdown, const std::string& file) {
  std::vector<ShellBlock> out;
  std::istringstream in(markdown);
  std::string line, previous;
  int number = 0;
  bool inside = false, collecting = false;
  for (; std::getline(in, line); previous = line) {
    ++number;
    const std::string text = trim(line);
    if (!starts_with(text, "```")) {
      if (collecting) out.back().text += line + "\n";
      continue;
    }
    if (inside) {  // a closing fence
      inside = collecting = false;
      continue;
    }
    inside = true;
    collecting = is_shell(trim(text.substr(3)));
    if (collecting) out.push_back({file, number, "", parse_marker(previous)});
  }
  return out;
}

std::string ci_text(const ShellBlock& block) {
  std::string text = block.text;
  for (const auto& s : block.plan.substitutions) {
    for (std::size_t at = text.find(s.from); at != std::string::npos;
         at = text.find(s.from, at + s.to.size()))
      text.replace(at, s.from.size(), s.to);
  }
  return text;
}

std::vector<Substitution> unmatched_substitutions(const ShellBlock& block) {
  std::vector<Substitution> out;
  for (const auto& s : block.plan.substitutions)
    if (block.text.find(s.from) == std::string::npos) out.push_back(s);
  return out;
}

std::string where(const ShellBlock& block) {
  return block.file + ":" + std::to_string(block.line);
}

}  // namespace pnp::docs
