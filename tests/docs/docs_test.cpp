// The docs test: every shell block of the user docs either runs here, against a fresh
// platform on free loopback ports, or its marker says why it does not (tests/docs/
// doc_blocks.h). A stale example fails the build.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "tests/docs/doc_blocks.h"
#include "tests/integration/child_process.h"

namespace pnp::docs {
namespace {

namespace fs = std::filesystem;
using integration::ChildProcess;
using integration::loopback;
using integration::TempDir;
using namespace std::chrono_literals;

// ---- the marker and block parser ----

TEST(DocBlocks, AMarkerSaysRunOrSkipWithAReason) {
  EXPECT_EQ(parse_marker("some prose").kind, BlockPlan::Kind::kUnmarked);
  EXPECT_EQ(parse_marker("<!-- docs-test: run -->").kind, BlockPlan::Kind::kRun);
  const BlockPlan skip = parse_marker("<!-- docs-test: skip: needs Docker -->");
  EXPECT_EQ(skip.kind, BlockPlan::Kind::kSkip);
  EXPECT_EQ(skip.reason, "needs Docker");
  EXPECT_EQ(parse_marker("<!-- docs-test: skip -->").kind, BlockPlan::Kind::kMalformed);
  EXPECT_EQ(parse_marker("<!-- docs-test: skip:   -->").kind, BlockPlan::Kind::kMalformed);
  EXPECT_EQ(parse_marker("<!-- docs-test: runs -->").kind, BlockPlan::Kind::kMalformed);
  EXPECT_EQ(parse_marker("<!-- docs-test: run").kind, BlockPlan::Kind::kMalformed);
  EXPECT_EQ(parse_marker("<!-- docs-test: run; --seeds 5 => --seeds 1 -->").kind,
            BlockPlan::Kind::kMalformed);
}

TEST(DocBlocks, CiSubstitutionsShrinkTheBudgetsAndAStaleOneIsFound) {
  const auto blocks = shell_blocks(
      "Intro\n"
      "<!-- docs-test: run; ci: --max-steps 60000 => --max-steps 3000; ci: --seeds 5 => --seeds "
      "1 -->\n"
      "```sh\n"
      "pnpctl pipeline --max-steps 60000 # twice: --max-steps 60000\n"
      "```\n"
      "```yaml\n"
      "not: a command\n"
      "```\n"
      "```bash\n"
      "echo unmarked\n"
      "```\n",
      "page.md");
  ASSERT_EQ(blocks.size(), 2u);
  EXPECT_EQ(where(blocks[0]), "page.md:3");
  EXPECT_EQ(ci_text(blocks[0]), "pnpctl pipeline --max-steps 3000 # twice: --max-steps 3000\n");
  const auto stale = unmatched_substitutions(blocks[0]);
  ASSERT_EQ(stale.size(), 1u);
  EXPECT_EQ(stale[0].from, "--seeds 5");
  EXPECT_EQ(blocks[1].plan.kind, BlockPlan::Kind::kUnmarked);
  EXPECT_EQ(blocks[1].text, "echo unmarked\n");
}

// ---- the docs themselves ----

fs::path source_dir() {
  return PNP_SOURCE_DIR;
}

std::string read(const fs::path& path) {
  return integration::read_file(path);
}

// README.md, then every other README one level down, then docs/*.md: the order a new
// user reads them in, which is the order their blocks run in.
std::vector<std::string> doc_files() {
  std::vector<std::string> out{"README.md"};
  std::vector<std::string> more;
  for (const auto& entry : fs::directory_iterator(source_dir())) {
    const fs::path readme = entry.path() / "README.md";
    if (entry.is_directory() && fs::exists(readme))
      more.push_back(fs::relative(readme, source_dir()).string());
  }
  std::sort(more.begin(), more.end());
  std::vector<std::string> docs;
  for (const auto& entry : fs::directory_iterator(source_dir() / "docs"))
    if (entry.path().extension() == ".md")
      docs.push_back(fs::relative(entry.path(), source_dir()).string());
  std::sort(docs.begin(), docs.end());
  out.insert(out.end(), more.begin(), more.end());
  out.insert(out.end(), docs.begin(), docs.end());
  return out;
}

std::vector<ShellBlock> all_blocks() {
  std::vector<ShellBlock> out;
  for (const auto& file : doc_files()) {
    auto blocks = shell_blocks(read(source_dir() / file), file);
    out.insert(out.end(), blocks.begin(), blocks.end());
  }
  return out;
}

TEST(Docs, EveryShellBlockRunsHereOrSaysWhyNot) {
  const auto blocks = all_blocks();
  EXPECT_GT(blocks.size(), 5u) << "the docs were not found under " << source_dir();
  for (const auto& block : blocks) {
    switch (block.plan.kind) {
      case BlockPlan::Kind::kUnmarked:
        ADD_FAILURE() << where(block)
                      << ": a shell block needs a marker on the line before its fence: "
                         "<!-- docs-test: run --> or <!-- docs-test: skip: REASON -->\n"
                      << block.text;
        break;
      case BlockPlan::Kind::kMalformed:
        ADD_FAILURE() << where(block) << ": bad docs-test marker: " << block.plan.reason;
        break;
      default:
        break;
    }
    for (const auto& s : unmatched_substitutions(block))
      ADD_FAILURE() << where(block) << ": ci substitution \"" << s.from
                    << "\" matches nothing in the block (edited since?)";
  }
}

std::string bin(const std::string& program) {
  return std::string(PNP_BIN_DIR) + "/" + program;
}

// The platform a user has running when they follow the README: every service on its
// own free loopback port over one store, and the simulated Panda controller. The
// addresses reach the commands through the environment (PNP_SIM_ADDRESS, ...), as a
// user's shell would set them for a deployment on other ports.
class Platform {
 public:
  explicit Platform(const TempDir& dir) : dir_(dir) {
    const std::string db = dir.file("pnp.db");
    start("sim", "PNP_SIM_ADDRESS", {bin("pnp-sim-server")});
    for (const std::string role : {"approach", "manipulate", "retract", "hlc", "e2e"}) {
      std::string env = role;
      std::transform(env.begin(), env.end(), env.begin(), ::toupper);
      start(role, "PNP_" + env + "_ADDRESS",
            {bin("pnp-train-server"), "--role", role, "--threads", "1", "--db", db});
    }
    start("inference", "PNP_INFERENCE_ADDRESS",
          {bin("pnp-inference-server"), "--db", db, "--create-db", "--reload-ms", "100"});
    start("robot", "PNP_ROBOT_CONTROLLER_ADDRESS",
          {bin("pnp-robot-sim"), "--object", "block", "--clock", "lockstep"});
  }

  bool ready() const { return failed_.empty(); }
  const std::string& failed() const { return failed_; }
  const std::vector<std::pair<std::string, std::string>>& environment() const { return env_; }

  std::string diagnostics() const {
    std::string out;
    for (const auto& server : servers_) out += server->diagnostics() + "\n";
    return out;
  }

 private:
  void start(const std::string& name, const std::string& env, std::vector<std::string> args) {
    args.push_back("--address");
    args.push_back("127.0.0.1:0");
    servers_.push_back(std::make_unique<ChildProcess>(name, std::move(args), dir_.path()));
    const int port = servers_.back()->port();
    if (port <= 0 && failed_.empty()) failed_ = servers_.back()->diagnostics();
    env_.emplace_back(env, loopback(port));
  }

  const TempDir& dir_;
  std::vector<std::unique_ptr<ChildProcess>> servers_;
  std::vector<std::pair<std::string, std::string>> env_;
  std::string failed_;
};

// The sandbox a block runs in: build/bin, build/python and the checked-in files the
// commands read (deploy/, docs/, examples/) are links; whatever a command writes stays here.
void make_sandbox(const fs::path& dir) {
  fs::create_directories(dir / "build");
  fs::create_directory_symlink(PNP_BIN_DIR, dir / "build" / "bin");
  fs::create_directory_symlink(fs::path(PNP_BIN_DIR).parent_path() / "python",
                               dir / "build" / "python");
  for (const char* checked_in : {"deploy", "docs", "examples"})
    fs::create_directory_symlink(source_dir() / checked_in, dir / checked_in);
}

std::string tail(const std::string& text, std::size_t n = 4000) {
  return text.size() <= n ? text : "..." + text.substr(text.size() - n);
}

TEST(Docs, TheRunnableBlocksRunAgainstAFreshPlatform) {
  TempDir dir("docs");
  const fs::path sandbox = dir.path() / "sandbox";
  make_sandbox(sandbox);
  Platform platform(dir);
  ASSERT_TRUE(platform.ready()) << platform.failed();
  auto env = platform.environment();
  env.emplace_back("PATH", std::string(PNP_BIN_DIR) + ":" + std::getenv("PATH"));
  int ran = 0;
  for (const auto& block : all_blocks()) {
    if (block.plan.kind != BlockPlan::Kind::kRun) continue;
    const std::string name = "block-" + std::to_string(++ran);
    const std::string script = "cd '" + sandbox.string() + "'\n" + ci_text(block);
    ChildProcess shell(name, {"/bin/bash", "-euo", "pipefail", "-c", script}, dir.path(), env);
    const auto status = shell.wait(900s);
    if (!status) shell.kill();
    EXPECT_TRUE(status && status->ok())
        << where(block) << " " << (status ? status->describe() : "did not finish in 900 s")
        << "\n--- block (as run in CI)\n"
        << ci_text(block) << "--- stdout\n"
        << tail(shell.stdout_text()) << "--- stderr\n"
        << tail(shell.stderr_text());
    if (!status || !status->ok()) std::fprintf(stderr, "%s\n", platform.diagnostics().c_str());
  }
  EXPECT_GT(ran, 0) << "no block is marked to run";
}

}  // namespace
}  // namespace pnp::docs
