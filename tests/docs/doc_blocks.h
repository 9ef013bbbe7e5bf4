#pragma once
// The shell blocks of the user docs (README.md, docs/*.md, ...), and what the docs test
// does with each: run it, or skip it for the reason its marker gives. A block's marker is
// an HTML comment on the line just before its fence, invisible when the page renders:
//
//   <!-- docs-test: run -->
//   <!-- docs-test: run; ci: --max-steps 60000 => --max-steps 3000 -->
//   <!-- docs-test: skip: needs Docker -->
//
// `ci: A => B` replaces every A in the block by B before it runs (small budgets in CI; the
// page keeps the numbers a user should type). Only sh, bash and shell blocks are commands.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace pnp::docs {

struct Substitution {
  std::string from, to;
};

struct BlockPlan {
  enum class Kind { kRun, kSkip, kUnmarked, kMalformed };
  Kind kind = Kind::kUnmarked;
  std::string reason;  // skip: why it is not run; malformed: what is wrong
  std::vector<Substitution> substitutions;
};

struct ShellBlock {
  std::string file;  // as given to shell_blocks
  int line = 0;      // the opening fence, 1-based
  std::string text;  // the lines between the fences
  BlockPlan plan;
};

// The plan a marker line (the line before a fence) gives; kUnmarked if it is no marker.
BlockPlan parse_marker(const std::string& line);

// Every shell block of a Markdown text, in order. `file` names it in the results.
std::vector<ShellBlock> shell_blocks(const std::string& markdown, const std::string& file);

// The block's text with its substitutions made, in order.
std::string ci_text(const ShellBlock& block);

// The substitutions whose text is not in the block: a page edited since its marker.
std::vector<Substitution> unmatched_substitutions(const ShellBlock& block);

// "README.md:86".
std::string where(const ShellBlock& block);

}  // namespace pnp::docs
