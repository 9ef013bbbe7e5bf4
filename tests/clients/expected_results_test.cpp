// pnpctl pipeline --expected: a run compared with the figures the docs give for its job.
#include "clients/pnpctl/expected_results.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "common/error.h"

namespace pnp::pnpctl {
namespace {

namespace fs = std::filesystem;

class ExpectedResults : public ::testing::Test {
 protected:
  void SetUp() override {
    std::ofstream(path_) << R"({"measured": [
      {"commit": "abc", "gemm_path": "openblas", "kernel": "OpenBLAS Haswell",
       "robot": "panda", "object": "block", "world": "gym", "actuation": "mocap", "seed": 0,
       "steps_to_target": {"approach": 3000, "manipulate": 4020, "retract": 7006, "hlc": 4000},
       "held_out_success": 0.95, "gateway": "9/10"},
      {"commit": "abc", "gemm_path": "openblas", "kernel": "OpenBLAS Zen",
       "robot": "panda", "object": "block", "world": "gym", "actuation": "mocap", "seed": 0,
       "steps_to_target": {"approach": 2011, "manipulate": 4020, "retract": 7006, "hlc": 4000},
       "held_out_success": 0.94, "gateway": "10/10"}]})";
  }
  void TearDown() override { fs::remove(path_); }

  static nlohmann::json results(long long approach_steps, double held_out) {
    nlohmann::json roles = nlohmann::json::array();
    const std::pair<const char*, long long> steps[] = {
        {"approach", approach_steps}, {"manipulate", 4020}, {"retract", 7006}, {"hlc", 4000}};
    for (const auto& [role, n] : steps) roles.push_back({{"role", role}, {"steps_to_target", n}});
    return {
        {"robot", "panda"},     {"object", "block"}, {"world", "gym"},
        {"actuation", "mocap"}, {"seed", 0},         {"gemm_path", "openblas"},
        {"code_commit", "def"}, {"roles", roles},    {"held_out", {{"success_rate", held_out}}}};
  }

  std::string path_ =
      (fs::temp_directory_path() / ("pnp_expected_" + std::to_string(::getpid()) + ".json"))
          .string();
};

TEST_F(ExpectedResults, ARunMatchingARowSaysWhichAndWhatTheGatewayShouldDo) {
  const std::string text = compare_with_expected(results(2011, 0.94), path_);
  EXPECT_EQ(text.rfind("as expected: exactly", 0), 0u) << text;
  EXPECT_NE(text.find("OpenBLAS Zen"), std::string::npos) << text;
  EXPECT_NE(text.find("robot gateway: 10/10 episodes expected"), std::string::npos) << text;
}

TEST_F(ExpectedResults, ADifferingRunNamesEveryFigureAndItsExpectedValue) {
  const std::string text = compare_with_expected(results(5000, 0.91), path_);
  EXPECT_EQ(text.rfind("differs from the figures", 0), 0u) << text;
  EXPECT_NE(text.find("approach: 5000 steps to target (expected 3000)"), std::string::npos) << text;
  EXPECT_NE(text.find("held-out success: 0.910 (expected 0.940)"), std::string::npos) << text;
  EXPECT_NE(text.find("this build is at commit def"), std::string::npos) << text;
}

TEST_F(ExpectedResults, OtherSettingsHaveNoFiguresAndSaySoWithWhatReproduces) {
  nlohmann::json other = results(2011, 0.94);
  other["seed"] = 1;
  const std::string text = compare_with_expected(other, path_);
  EXPECT_EQ(text.rfind("no figures in", 0), 0u) << text;
  EXPECT_NE(text.find("seed 1"), std::string::npos) << text;
}

TEST_F(ExpectedResults, AFileOfAnotherShapeIsRefusedNamingTheFlag) {
  std::ofstream(path_) << "[1, 2]";
  try {
    compare_with_expected(results(2011, 0.94), path_);
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--expected"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pnp::pnpctl
