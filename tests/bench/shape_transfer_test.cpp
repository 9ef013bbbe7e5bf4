// The shape-transfer study's parts: a gateway cell plays real episodes through the
// inference service and the controller stand-in (in process, loopback), the same scenes
// give the same outcomes, and the table reports what the cells hold.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "bench/shape_transfer/gateway_cell.h"
#include "bench/shape_transfer/transfer_report.h"
#include "nn/checkpoint_io.h"

namespace pnp::bench {
namespace {

namespace fs = std::filesystem;

HierarchyBlobs checked_in_hierarchy() {
  HierarchyBlobs blobs;
  for (std::size_t k = 0; k < kHierarchyRoles.size(); ++k) {
    blobs.roles[k] = nn::read_file(
        (fs::path(PNP_TEST_DATA_DIR) / "panda_block" / (std::string(kHierarchyRoles[k]) + ".ckpt"))
            .string());
  }
  return blobs;
}

class ShapeTransferCell : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("pnp_shape_transfer_test_" +
            std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  nlohmann::json play(const std::string& cell, std::uint64_t first_seed) {
    GatewayCellSpec spec{
        sim::ObjectShape::kBlock, sim::WorldProfile::kPaper, &config_, 2, first_seed, dir_ / cell};
    return play_gateway_cell(spec, {serving::PolicyKind::kHierarchy, checked_in_hierarchy(), {}});
  }

  fs::path dir_;
  robot::GatewayConfig config_ =
      robot::GatewayConfig::load(std::string(PNP_SOURCE_DIR) + "/deploy/robot/gateway.json");
};

TEST_F(ShapeTransferCell, PlaysEveryEpisodeThroughTheGatewayAndLogsItsEvents) {
  const nlohmann::json cell = play("first", 880000);
  EXPECT_EQ(cell.at("episodes").get<int>(), 2);
  EXPECT_EQ(cell.at("seeds"), nlohmann::json({880000, 880001}));
  EXPECT_GT(cell.at("cycles").get<int>(), 0);  // the policy drove the arm
  EXPECT_TRUE(cell.at("gateway_errors").empty());
  EXPECT_EQ(cell.at("refused_targets").get<int>(), 0);
  const int successes = cell.at("successes").get<int>();
  EXPECT_GE(successes, 0);
  EXPECT_LE(successes, 2);
  EXPECT_DOUBLE_EQ(cell.at("success_rate").get<double>(), successes / 2.0);
  EXPECT_TRUE(fs::exists(dir_ / "first" / "pnp.db"));
  EXPECT_GT(fs::file_size(dir_ / "first" / "gateway_events.jsonl"), 0u);
}

TEST_F(ShapeTransferCell, TheSameScenesGiveTheSameEpisodes) {
  const nlohmann::json a = play("a", 880010);
  const nlohmann::json b = play("b", 880010);
  EXPECT_EQ(a.at("successes"), b.at("successes"));
  EXPECT_EQ(a.at("cycles"), b.at("cycles"));
  EXPECT_EQ(a.at("ends"), b.at("ends"));
}

TEST(ShapeTransferReport, TheTableShowsEachCellAndTheFineTuningSteps) {
  const std::vector<TransferColumn> columns{{"fine_tuned", "(a) tuned"},
                                            {"block_hierarchy", "(b) block"}};
  auto cell = [](int successes, int episodes, int errors) {
    nlohmann::json c{{"successes", successes},
                     {"episodes", episodes},
                     {"success_rate", static_cast<double>(successes) / episodes},
                     {"gateway_errors", nlohmann::json::array()}};
    for (int k = 0; k < errors; ++k) c["gateway_errors"].push_back({{"seed", k}});
    return c;
  };
  nlohmann::json cells;
  cells["block"]["block_hierarchy"] = cell(199, 200, 0);
  cells["cylinder"]["block_hierarchy"] = cell(150, 200, 0);
  cells["cylinder"]["fine_tuned"] = cell(190, 200, 1);
  cells["block"]["block_hierarchy"]["arm_world"] = {
      {"success_at_episode_end", 0.99},
      {"success_any_step", 0.995},
      {"disagreements_with_gateway", nlohmann::json::array()}};
  nlohmann::json fine_tuning;
  fine_tuning["cylinder"] = nlohmann::json::array({{{"role", "retract/cylinder"},
                                                    {"reached", true},
                                                    {"steps_to_target", 12000},
                                                    {"train_env_steps", 12000}},
                                                   {{"role", "(a+) hlc/cylinder"},
                                                    {"reached", false},
                                                    {"steps_to_target", nullptr},
                                                    {"train_env_steps", 60000}}});
  const std::string md = transfer_markdown({"block", "cylinder"}, columns, cells, fine_tuning);
  EXPECT_NE(md.find("| shape | (a) tuned | (b) block |"), std::string::npos) << md;
  EXPECT_NE(md.find("| block | - | 0.995 (199/200); arm world 0.995, 0 scenes differ | - "
                    "(trained on block) |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| cylinder | 0.950 (190/200), 1 refused readings | 0.750 (150/200) | "
                    "retract/cylinder 12.0k, (a+) hlc/cylinder 60.0k (cap, not reached) |"),
            std::string::npos)
      << md;
}

}  // namespace
}  // namespace pnp::bench
