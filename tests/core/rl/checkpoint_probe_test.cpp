#include "rl/checkpoint_probe.h"

#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <tuple>

#include "common/error.h"
#include "nn/checkpoint_io.h"
#include "rl/checkpoint_sections.h"
#include "rl/choreographer_checkpoint.h"
#include "rl/ddpg_her_agent.h"
#include "rl/expert_checkpoint.h"
#include "rl/network_limits.h"

namespace pnp::rl {
namespace {

std::vector<std::uint8_t> expert_blob(const std::string& role, std::vector<int> hidden = {16, 16}) {
  DdpgHerConfig config;
  config.hidden = std::move(hidden);
  Rng rng(3);
  DdpgHerAgent agent(config, rng);
  ExpertMeta meta;
  meta.role = role;
  meta.algorithm = "ddpg_her";
  meta.robot = "fetch";
  meta.object = "block";
  meta.hidden = config.hidden;
  return save_expert(meta, agent.actor(), nullptr, agent.observation_normalizer(),
                     agent.goal_normalizer());
}

std::vector<std::uint8_t> choreographer_blob(ChoreographerSpec spec = {{16}, 4}) {
  ChoreographerNet net(spec);
  Rng rng(4);
  net.initialise(rng);
  return save_choreographer({"fetch", "block", "gym", net.spec(), 0, 0, 4, "test"}, net);
}

// The same file with its metadata edited and every other section copied as it was: a
// file whose checksum a store would accept.
std::vector<std::uint8_t> with_meta(const std::vector<std::uint8_t>& blob, const char* kind,
                                    const std::function<void(nlohmann::json&)>& edit,
                                    const std::vector<std::string>& sections) {
  const nn::CheckpointReader r(blob);
  nlohmann::json meta = read_meta(r, kind);
  edit(meta);
  nn::CheckpointWriter w;
  write_meta(w, meta);
  for (const auto& name : sections) w.add(name, r.bytes(name));
  return w.finish();
}

const std::vector<std::string> kExpertSections{"actor",          "obs_norm.sum",  "obs_norm.sumsq",
                                               "obs_norm.count", "goal_norm.sum", "goal_norm.sumsq",
                                               "goal_norm.count"};

// The code f was refused with; nullopt if it was accepted.
std::optional<ErrorCode> code_of(const std::function<void()>& f, std::string* message = nullptr) {
  try {
    f();
  } catch (const Error& e) {
    if (message) *message = e.what();
    return e.code();
  }
  return std::nullopt;
}

TEST(CheckpointProbe, ServableCheckpointsPass) {
  for (const char* role : {"approach", "manipulate", "retract", "e2e"})
    EXPECT_NO_THROW(probe_checkpoint(role, expert_blob(role), "checkpoint_id 1")) << role;
  EXPECT_NO_THROW(probe_checkpoint("hlc", choreographer_blob(), "checkpoint_id 2"));
}

// The 51 KB file that aborted every replica: a valid file whose metadata asks for two
// layers of 20000 units. Refused by the bound, before anything is allocated.
TEST(CheckpointProbe, HugeWidthsInTheMetadataAreRefusedBeforeAllocating) {
  const auto huge = with_meta(
      expert_blob("retract"), "subtask_expert",
      [](nlohmann::json& m) {
        m["hidden"] = {20000, 20000};
      },
      kExpertSections);
  EXPECT_LT(huge.size(), 64u * 1024);
  std::string message;
  EXPECT_EQ(code_of([&] { load_expert(huge); }, &message), ErrorCode::kInvalidArgument);
  EXPECT_NE(message.find("checkpoint hidden[0]"), std::string::npos) << message;
  EXPECT_EQ(code_of([&] { probe_checkpoint("retract", huge, "checkpoint_id 7"); }, &message),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(message.rfind("checkpoint_id 7: checkpoint hidden[0]", 0), 0u) << message;

  const auto deep = with_meta(
      expert_blob("retract"), "subtask_expert",
      [](nlohmann::json& m) { m["hidden"] = std::vector<int>(kMaxHiddenLayers + 1, 8); },
      kExpertSections);
  EXPECT_EQ(code_of([&] { load_expert(deep); }), ErrorCode::kInvalidArgument);
  // Widths whose product overflows an int: refused by the bound, not wrapped.
  const auto wide = with_meta(choreographer_blob(), "choreographer",
                              [](nlohmann::json& m) { m["lstm"] = 100000; },
                              {"block0", "norm.sum", "norm.sumsq", "norm.count"});
  EXPECT_EQ(code_of([&] { load_choreographer(wide); }, &message), ErrorCode::kInvalidArgument);
  EXPECT_NE(message.find("checkpoint lstm"), std::string::npos) << message;
  // Found by the fuzzer once it got past the checksum: a kind that is not a string.
  const auto numbered =
      with_meta(choreographer_blob(), "choreographer", [](nlohmann::json& m) { m["kind"] = 32; },
                {"block0", "norm.sum", "norm.sumsq", "norm.count"});
  EXPECT_EQ(code_of([&] { load_choreographer(numbered); }, &message), ErrorCode::kInvalidArgument);
  EXPECT_EQ(message, "checkpoint kind: expected choreographer, got 32");
}

// Both kinds read the world and provenance fields through one parser: a file written before
// a field was kept gets what files before it held, and a field every file has is required.
TEST(CheckpointProbe, AnOlderFilesMissingFieldsTakeWhatFilesBeforeThemHeld) {
  const auto forget = [](nlohmann::json& m) {
    for (const char* field : {"world", "actuation", "code_commit", "gemm_path"}) m.erase(field);
  };
  const LoadedExpert expert =
      load_expert(with_meta(expert_blob("approach"), "subtask_expert", forget, kExpertSections));
  const auto chor_blob = choreographer_blob();
  std::vector<std::string> chor_sections{"norm.sum", "norm.sumsq", "norm.count"};
  for (int b = 0; nn::CheckpointReader(chor_blob).has("block" + std::to_string(b)); ++b)
    chor_sections.push_back("block" + std::to_string(b));
  const LoadedChoreographer chor =
      load_choreographer(with_meta(chor_blob, "choreographer", forget, chor_sections));
  for (const auto& [world, actuation, commit, gemm] :
       {std::tuple(expert.meta.world, expert.meta.actuation, expert.meta.code_commit,
                   expert.meta.gemm_path),
        std::tuple(chor.meta.world, chor.meta.actuation, chor.meta.code_commit,
                   chor.meta.gemm_path)}) {
    EXPECT_EQ(world, "paper");
    EXPECT_EQ(actuation, "mocap");
    EXPECT_EQ(commit, "");
    EXPECT_EQ(gemm, "");
  }
  EXPECT_EQ(chor.meta.seed, 4u) << "the rest as written";
  EXPECT_EQ(chor.meta.robot, "fetch");
  const auto no_seed = [](nlohmann::json& m) { m.erase("seed"); };
  EXPECT_EQ(code_of([&] {
              load_choreographer(with_meta(chor_blob, "choreographer", no_seed, chor_sections));
            }),
            ErrorCode::kDataLoss);
  EXPECT_EQ(
      code_of([&] {
        load_expert(with_meta(expert_blob("approach"), "subtask_expert", no_seed, kExpertSections));
      }),
      ErrorCode::kDataLoss);
}

// Widths within bounds but not those the sections hold: DATA_LOSS from the sizes alone.
TEST(CheckpointProbe, SectionSizesAreCheckedAgainstTheMetadata) {
  const auto mismatched = with_meta(
      expert_blob("retract", {16, 16}), "subtask_expert",
      [](nlohmann::json& m) {
        m["hidden"] = {64, 64};
      },
      kExpertSections);
  std::string message;
  EXPECT_EQ(code_of([&] { load_expert(mismatched); }, &message), ErrorCode::kDataLoss);
  EXPECT_NE(message.find("section \"actor\""), std::string::npos) << message;
  EXPECT_EQ(nn::Mlp::flat_size({3, {16}, 2}), 48u + 16 + 32 + 16) << "aligned as params() is";
}

TEST(CheckpointProbe, NonFiniteWeightsAndOtherRolesAreRefused) {
  const auto blob = expert_blob("approach");
  const nn::CheckpointReader r(blob);
  std::vector<float> actor = r.floats("actor", r.bytes("actor").size() / sizeof(float));
  actor[0] = std::numeric_limits<float>::quiet_NaN();
  nn::CheckpointWriter w;
  write_meta(w, read_meta(r, "subtask_expert"));
  w.add_floats("actor", actor);
  for (const auto& name : kExpertSections)
    if (name != "actor") w.add(name, r.bytes(name));
  std::string message;
  EXPECT_EQ(
      code_of([&] { probe_checkpoint("approach", w.finish(), "checkpoint_ids[1] 3"); }, &message),
      ErrorCode::kInvalidArgument);
  EXPECT_NE(message.find("non-finite"), std::string::npos) << message;

  EXPECT_EQ(code_of([&] { probe_checkpoint("retract", blob, "checkpoint_id 3"); }, &message),
            ErrorCode::kInvalidArgument);
  EXPECT_NE(message.find("role approach"), std::string::npos) << message;
  EXPECT_EQ(code_of([&] { probe_checkpoint("hlc", blob, "checkpoint_id 3"); }),
            ErrorCode::kInvalidArgument)
      << "an expert's file is not a choreographer's";
  EXPECT_EQ(code_of([&] {
              probe_checkpoint("approach", {blob.data(), 20}, "checkpoint_id 3");
            }),
            ErrorCode::kDataLoss);
}

}  // namespace
}  // namespace pnp::rl
