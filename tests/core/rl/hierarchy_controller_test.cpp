#include "rl/hierarchy_controller.h"

#include <gtest/gtest.h>

#include "common/error.h"
#include "rl/a3c_trainer.h"
#include "rl/hlc_episode.h"
#include "sim/pick_place_env.h"
#include "sim/scripted_expert.h"
#include "sim/world_layout.h"

namespace pnp::rl {
namespace {

HierarchyController::Experts scripted_experts() {
  return {std::make_unique<sim::ScriptedPolicy>(), std::make_unique<sim::ScriptedPolicy>(),
          std::make_unique<sim::ScriptedPolicy>()};
}

// The controller, stepped by hand, makes exactly the greedy episode's decisions: the
// inference service and the gateway run the hierarchy that was evaluated.
TEST(HierarchyController, StepByStepEqualsTheGreedyEpisode) {
  const auto world = sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock);
  const double width = 2 * world->object_spec().half_width_m;
  // The paper's choreographer (no predicate inputs, no masking) on the last seed.
  for (std::uint64_t init_seed : {1u, 2u, 3u}) {
    const bool paper = init_seed == 3;
    ChoreographerNet net({{32, 32}, 8, !paper, !paper});
    Rng init(init_seed);
    net.initialise(init);
    sim::ScriptedPolicy scripted;
    HierarchyController controller(net, scripted_experts(), width, sim::layout::kEpisodeSteps);
    for (std::uint64_t episode = 0; episode < 4; ++episode) {
      const std::uint64_t seed = derive_seed(init_seed * 100, episode);
      sim::PickPlaceEnv reference_env(world);
      Rng unused(0);
      ChoreographerNet reference_net = net;
      const HlcEpisode reference = run_hlc_episode(
          reference_env, reference_net, {&scripted, &scripted, &scripted}, seed, false, unused);

      sim::PickPlaceEnv env(world);
      env.reset(seed);
      controller.reset();
      std::string choices;
      sim::StepResult last;
      while (!env.needs_reset()) {
        const auto d = controller.act(env.observation(), env.episode_goal());
        if (d.decided) choices += "AMR"[static_cast<int>(d.subtask)];
        const sim::Objective objective =
            d.placed ? sim::Objective::kTask : sim::objective_of(d.subtask);
        last = env.step(d.action, sim::objective_goal(objective, env.task_state()), objective);
      }
      EXPECT_EQ(choices, choice_string(reference))
          << "init " << init_seed << " episode " << episode;
      EXPECT_EQ(last.task_success, reference.success);
    }
  }
}

// A subtask whose objective never fires ends at its cap: the cap of the episode the last
// reset declared, so a mocap-trained hierarchy played on the arm's 75 steps gets the arm's.
TEST(HierarchyController, SubtaskCapsFollowTheDeclaredEpisode) {
  ChoreographerNet net({{8}, 4});
  Rng init(0);
  net.initialise(init);
  HierarchyController controller(net, scripted_experts(), 0.05, sim::layout::kEpisodeSteps);
  const sim::Observation still = sim::Observation::Zero();  // nothing moves: nothing is done
  const sim::Goal goal(1.3, 0.7, 0.45);
  // The first subtask and the steps it ran before the choreographer decided again.
  const auto first_span = [&] {
    const sim::Subtask first = controller.act(still, goal).subtask;
    int steps = 1;
    while (steps < 1000 && !controller.act(still, goal).decided) ++steps;
    return std::pair{first, steps};
  };
  EXPECT_EQ(controller.episode_steps(), sim::layout::kEpisodeSteps);
  const auto [first_50, steps_50] = first_span();
  EXPECT_EQ(steps_50, sim::step_cap(first_50, sim::layout::kEpisodeSteps));

  controller.reset(sim::layout::kArmEpisodeSteps);
  EXPECT_EQ(controller.episode_steps(), sim::layout::kArmEpisodeSteps);
  const auto [first_75, steps_75] = first_span();
  EXPECT_EQ(first_75, first_50) << "the same choreographer, the same first choice";
  EXPECT_EQ(steps_75, sim::step_cap(first_75, sim::layout::kArmEpisodeSteps));
  EXPECT_GT(steps_75, steps_50);

  controller.reset();  // keeps the last declared length
  EXPECT_EQ(first_span().second, steps_75);
  EXPECT_THROW(controller.reset(0), Error) << "an empty episode has no caps";
}

TEST(HierarchyController, RefusesANonFiniteObservationNamingIt) {
  ChoreographerNet net({{8}, 4});
  Rng init(0);
  net.initialise(init);
  HierarchyController controller(net, scripted_experts(), 0.05, sim::layout::kEpisodeSteps);
  sim::Observation o = sim::Observation::Zero();
  o(4) = std::numeric_limits<double>::quiet_NaN();
  try {
    controller.act(o, sim::Goal(1.3, 0.7, 0.45));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("observation"), std::string::npos) << e.what();
  }
  EXPECT_EQ(controller.steps(), 0) << "a refused request changes nothing";
}

}  // namespace
}  // namespace pnp::rl
