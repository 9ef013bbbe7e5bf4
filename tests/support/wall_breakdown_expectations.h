#pragma once
// What every trainer's wall-time breakdown must satisfy (rl/wall_breakdown.h): each phase
// measured, none counted twice, evaluation as the stop rule's clock has it, and at least
// `min_report_s` in the callbacks that write checkpoints and the store.

#include <gtest/gtest.h>

#include "rl/training_progress.h"

namespace pnp::rl {

inline void expect_a_whole_breakdown(const TrainingResult& result, double min_report_s) {
  const WallBreakdown& b = result.breakdown;
  EXPECT_GT(b.rollout_s, 0);
  EXPECT_GT(b.update_s, 0);
  EXPECT_NEAR(b.eval_s, result.eval_wall_s, 1e-3);
  EXPECT_GE(b.report_s, min_report_s);
  EXPECT_GE(b.other_s, 0);
  EXPECT_DOUBLE_EQ(b.total_s, b.rollout_s + b.update_s + b.eval_s + b.report_s + b.other_s);
  EXPECT_LE(b.total_s, result.wall_s + 1e-3);
}

}  // namespace pnp::rl
