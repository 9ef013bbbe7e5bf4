// Every program says which code it is: `--version` prints "<program> <release> (commit
// <commit>)" and exits 0, the release and commit being this build's.
#include "common/version.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "tests/integration/child_process.h"

namespace pnp::integration {
namespace {

// The build's programs: every pnp-* and pnpctl in the output directory.
std::vector<std::string> programs() {
  std::vector<std::string> out;
  for (const auto& entry : std::filesystem::directory_iterator(PNP_BIN_DIR)) {
    const std::string name = entry.path().filename().string();
    if (name == "pnpctl" || name.rfind("pnp-", 0) == 0) out.push_back(name);
  }
  return out;
}

TEST(Version, EveryProgramNamesItsReleaseAndCommit) {
  TempDir dir("version");
  const std::vector<std::string> found = programs();
  const std::set<std::string> listed(found.begin(), found.end());
  // Not vacuous: the servers, the clients and the tools are among them.
  for (const char* expected : {"pnp-sim-server", "pnp-train-server", "pnp-inference-server",
                               "pnp-store-server", "pnp-robot-sim", "pnp-robot-gateway",
                               "pnp-dashboard", "pnpctl", "pnp-train", "pnp-paper-table"}) {
    EXPECT_TRUE(listed.count(expected)) << expected << " is not in " << PNP_BIN_DIR;
  }
  for (const std::string& name : found) {
    ChildProcess program(name, {std::string(PNP_BIN_DIR) + "/" + name, "--version"}, dir.path());
    const auto status = program.wait(std::chrono::seconds(30));
    ASSERT_TRUE(status) << name << " --version did not end";
    EXPECT_TRUE(status->ok()) << name << ": " << status->describe();
    EXPECT_EQ(read_file(program.stdout_path()), version_text(name) + "\n") << name;
  }
}

TEST(Version, TheTextIsTheReleaseAndTheCommit) {
  EXPECT_EQ(version_text("pnpctl"), "pnpctl " + std::string(release_version()) + " (commit " +
                                        std::string(build_commit()) + ")");
  EXPECT_FALSE(release_version().empty());
  EXPECT_FALSE(build_commit().empty());
}

}  // namespace
}  // namespace pnp::integration
