#include "training/preset.h"

#include <gtest/gtest.h>

#include "common/error.h"

namespace pnp::training {
namespace {

constexpr const char* kRoles[] = {"approach", "manipulate", "retract", "hlc", "e2e"};

TEST(Preset, EveryRoleOfEveryPresetIsAValidSpecThatRoundTripsThroughJson) {
  for (const Preset& preset : presets()) {
    for (const char* role : kRoles) {
      const TrainingSpec spec = preset_spec(preset, role);
      EXPECT_NO_THROW(spec.validate()) << preset.name << " " << role;
      EXPECT_EQ(spec.preset, preset.name);
      EXPECT_EQ(to_json(spec_from_json(to_json(spec))), to_json(spec)) << preset.name << role;
    }
  }
}

TEST(Preset, TheDefaultUsesNoDemonstrations) {
  const Preset& preset = find_preset(kDefaultPreset, "preset");
  EXPECT_FALSE(preset.uses_demonstrations);
  EXPECT_EQ(preset.ddpg.demo_episodes, 0);
  EXPECT_EQ(preset.ddpg.demo_bc_weight, 0);
  EXPECT_EQ(preset.ddpg.demo_pretrain_updates, 0);
}

// The paper's conditions: what the published method had, nothing of ours.
TEST(Preset, PaperIsThePublishedMethod) {
  const Preset& p = find_preset("paper", "preset");
  EXPECT_FALSE(p.uses_demonstrations);
  EXPECT_EQ(p.ddpg.demo_episodes, 0);
  EXPECT_EQ(p.ddpg.demo_bc_weight, 0);
  EXPECT_TRUE(p.scripted_gripper);
  EXPECT_FALSE(p.chained_experts);
  EXPECT_EQ(p.ddpg.updates_per_cycle, 40);
  EXPECT_EQ(p.ddpg.updates_per_transition, 0);
  EXPECT_EQ(p.ddpg.episodes_per_cycle, 2);
  EXPECT_FALSE(p.a3c.network.predicate_inputs);
  EXPECT_FALSE(p.a3c.network.mask_finished);
  EXPECT_EQ(p.expert_stop.eval_interval_steps, 5000) << "once per epoch";
  EXPECT_EQ(p.ddpg.action_l2, 1.0) << "the original's action penalty";
  EXPECT_FALSE(effective_ddpg(preset_spec(p, "retract")).learn_gripper);
}

// ours+demos is ours and demonstrations, nothing else, and says so.
TEST(Preset, OursWithDemonstrationsDiffersFromOursOnlyInItsDemonstrations) {
  const Preset& ours = find_preset("ours", "preset");
  const Preset& demos = find_preset("ours+demos", "preset");
  EXPECT_TRUE(demos.uses_demonstrations);
  EXPECT_GT(demos.ddpg.demo_episodes, 0);
  for (const char* role : kRoles) {
    nlohmann::json a = to_json(preset_spec(ours, role));
    nlohmann::json b = to_json(preset_spec(demos, role));
    for (auto* j : {&a, &b}) {
      j->erase("preset");
      for (const char* key : {"demo_episodes", "demo_pretrain_updates", "demo_bc_weight"})
        (*j)["ddpg"].erase(key);
    }
    EXPECT_EQ(a, b) << role;
  }
  EXPECT_EQ(to_json(demos)["uses_demonstrations"], true);
  EXPECT_EQ(to_json(ours)["uses_demonstrations"], false);
}

// Ours penalises motion less than the original (docs/LEARNING.md, "Action penalty"); every
// role of ours and ours+demos gets that penalty.
TEST(Preset, OursPenalisesMotionLessThanTheOriginal) {
  for (const char* name : {"ours", "ours+demos"}) {
    const Preset& p = find_preset(name, "preset");
    EXPECT_EQ(p.ddpg.action_l2, 0.2) << name;
    for (const char* role : {"approach", "manipulate", "retract", "e2e"})
      EXPECT_EQ(preset_spec(p, role).ddpg.action_l2, 0.2) << name << " " << role;
  }
}

// Ours stops experts and choreographer above the hierarchy's 95% (a stop rule on 100
// episodes accepts a policy a little below its target); the paper stops at 95%.
TEST(Preset, OursStopsEveryRoleAt97Percent) {
  for (const char* name : {"ours", "ours+demos"}) {
    const Preset& p = find_preset(name, "preset");
    for (const char* role : {"approach", "manipulate", "retract", "hlc"})
      EXPECT_EQ(preset_spec(p, role).stop.target_success, 0.97) << name << " " << role;
  }
  EXPECT_EQ(preset_spec(find_preset("paper", "preset"), "hlc").stop.target_success, 0.95);
}

// Every preset drives the gripper as the paper's code does: measured, a learned gripper
// costs ours steps and held-out success (docs/RESULTS.md, "Preset `ours` scripts the gripper").
TEST(Preset, EveryPresetScriptsTheGripper) {
  for (const char* name : {"paper", "ours", "ours+demos"}) {
    const Preset& p = find_preset(name, "preset");
    EXPECT_TRUE(p.scripted_gripper) << name;
    for (const char* role : {"approach", "manipulate", "retract"})
      EXPECT_FALSE(effective_ddpg(preset_spec(p, role)).learn_gripper) << name << " " << role;
    EXPECT_TRUE(effective_ddpg(preset_spec(p, "e2e")).learn_gripper)
        << name << ": the end-to-end baseline has no scripted gripper to keep";
  }
}

// Ours leans the choreographer toward the experts' order; the paper's has no prior.
TEST(Preset, OnlyOursHasAChainPrior) {
  EXPECT_EQ(preset_spec(find_preset("ours", "preset"), "hlc").a3c.network.chain_prior, 2.0);
  EXPECT_EQ(preset_spec(find_preset("ours+demos", "preset"), "hlc").a3c.network.chain_prior, 2.0);
  EXPECT_EQ(preset_spec(find_preset("paper", "preset"), "hlc").a3c.network.chain_prior, 0.0);
}

TEST(Preset, AnUnknownNameIsRefusedNamingTheFieldAndTheNames) {
  try {
    find_preset("fast", "--preset");
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_STREQ(e.what(),
                 "--preset: expected one of [\"paper\",\"ours\",\"ours+demos\"], got \"fast\"");
  }
}

}  // namespace
}  // namespace pnp::training
