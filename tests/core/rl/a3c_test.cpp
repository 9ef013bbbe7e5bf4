#include <gtest/gtest.h>

#include "common/error.h"
#include "rl/a3c_trainer.h"

namespace pnp::rl {
namespace {

HlcTrainingOutput short_run(int workers) {
  HlcTrainingConfig config;
  config.seed = 11;
  config.a3c.workers = workers;
  config.a3c.network = {{32, 32}, 8};
  config.stop.max_steps = 600;
  config.stop.eval_interval_steps = 300;
  config.stop.eval_episodes = 4;
  config.eval_threads = 2;
  const sim::ScriptedPolicy scripted;
  return train_choreographer(sim::WorldModel::load(sim::Robot::kFetch, sim::ObjectShape::kBlock),
                             {&scripted, &scripted, &scripted}, config);
}

// Workers run concurrently, but gradients are applied in ticket order: the same seed and
// worker count give the same network whatever the scheduling.
TEST(A3c, ReproducibleForAGivenSeedAndWorkerCount) {
  const auto a = short_run(3);
  const auto b = short_run(3);
  ASSERT_EQ(a.result.curve.size(), b.result.curve.size());
  for (std::size_t i = 0; i < a.result.curve.size(); ++i) {
    EXPECT_EQ(a.result.curve[i].env_steps, b.result.curve[i].env_steps);
    EXPECT_EQ(a.result.curve[i].task_success, b.result.curve[i].task_success);
  }
  auto pa = a.net->parameter_blocks();
  auto pb = b.net->parameter_blocks();
  for (std::size_t k = 0; k < pa.size(); ++k)
    EXPECT_TRUE(std::equal(pa[k].begin(), pa[k].end(), pb[k].begin()));
  EXPECT_GE(a.result.train_env_steps, 600);
  EXPECT_EQ(a.result.train_env_steps % 50, 0) << "every choreographer episode runs all 50 steps";
  // The other two workers' episodes in flight at the stop ran, so they count.
  EXPECT_EQ(a.result.train_env_steps, a.result.curve.back().env_steps + 2 * 50);
}

TEST(A3c, RefusesInvalidConfiguration) {
  A3cConfig c;
  c.workers = 0;
  EXPECT_THROW(c.validate(), Error);
  c = {};
  c.gamma = 1.5;
  EXPECT_THROW(c.validate(), Error);
}

}  // namespace
}  // namespace pnp::rl
