#include "tools/paper_table/experiments.h"

#include <memory>

#include "arm_sim/arm_env_factory.h"
#include "common/rng.h"
#include "common/thread_pool.h"
#include "rl/a3c_trainer.h"
#include "rl/learned_expert.h"
#include "rl/seed_streams.h"

namespace pnp::tools {
namespace {

// Steps a part contributes to the table: to the target if reached, else all it spent.
long long counted_steps(const rl::TrainingResult& r) {
  return r.reached ? r.steps_to_target : r.train_env_steps;
}

void add(MethodRun& run, std::string role, rl::TrainingResult result) {
  run.total_steps += counted_steps(result);
  run.total_wall_s += rl::wall_to_target(result);
  run.reached = run.reached && result.reached;
  run.roles.push_back({std::move(role), std::move(result)});
}

}  // namespace

MethodRun run_hierarchy(const std::string& method, rl::ExpertAlgorithm algorithm,
                        std::uint64_t seed, const ExperimentSettings& s, const Progress& progress) {
  const auto envs =
      arm_sim::make_env_factory(s.robot, s.object, s.world, sim::default_actuation(s.robot));
  const sim::EnvFactory& world = *envs;
  MethodRun run{method, seed, {}, true, 0, 0, -1};
  std::vector<std::unique_ptr<rl::LearnedExpert>> experts;
  for (sim::Subtask subtask : sim::kAllSubtasks) {
    rl::SubtaskTrainingConfig config;
    config.algorithm = algorithm;
    config.ddpg = s.ddpg;
    config.subtask = subtask;
    config.seed = derive_seed(seed, static_cast<std::uint64_t>(subtask));
    config.stop = s.expert_stop;
    config.threads = s.threads;
    if (s.chained) {
      for (std::size_t k = 0; k < experts.size(); ++k) config.prefix[k] = experts[k].get();
    }
    const std::string role(sim::subtask_name(subtask));
    auto out = rl::train_subtask_expert(
        world, config, [&](const rl::CurvePoint& p) { progress(method, seed, role, p); });
    experts.push_back(std::make_unique<rl::LearnedExpert>(
        out.agent->snapshot(),
        config.ddpg.learn_gripper ? std::nullopt
                                  : std::optional<sim::GripperScript>(config.ddpg.gripper_script)));
    add(run, role, std::move(out.result));
  }
  const std::array<const sim::SubtaskPolicy*, sim::kNumSubtasks> prototypes{
      experts[0].get(), experts[1].get(), experts[2].get()};
  rl::HlcTrainingConfig hlc;
  hlc.seed = derive_seed(seed, 3);
  hlc.stop = s.hlc_stop;
  hlc.a3c = s.a3c;
  hlc.eval_threads = s.threads;
  auto out = rl::train_choreographer(
      world, prototypes, hlc, [&](const rl::CurvePoint& p) { progress(method, seed, "hlc", p); });
  if (s.held_out_episodes > 0) {
    ThreadPool pool(s.threads);
    run.held_out_success =
        rl::evaluate_choreographer(world, *out.net, prototypes, s.held_out_episodes,
                                   rl::stream_seed(seed, rl::Stream::kHeldOutTest), pool)
            .success_rate;
  }
  add(run, "hlc", std::move(out.result));
  return run;
}

MethodRun run_end_to_end(std::uint64_t seed, const ExperimentSettings& s,
                         const Progress& progress) {
  const auto envs =
      arm_sim::make_env_factory(s.robot, s.object, s.world, sim::default_actuation(s.robot));
  const sim::EnvFactory& world = *envs;
  MethodRun run{"e2e", seed, {}, true, 0, 0, -1};
  rl::SubtaskTrainingConfig config;
  config.algorithm = rl::ExpertAlgorithm::kEndToEnd;
  config.ddpg = s.ddpg;
  config.seed = derive_seed(seed, 4);
  config.stop = s.e2e_stop;
  config.threads = s.threads;
  config.ddpg.learn_gripper = true;  // the baseline has no scripted gripper to keep
  config.ddpg.random_gripper = true;
  auto out = rl::train_subtask_expert(
      world, config, [&](const rl::CurvePoint& p) { progress("e2e", seed, "e2e", p); });
  add(run, "e2e", std::move(out.result));
  return run;
}

}  // namespace pnp::tools
