#pragma once
// A training result and its learning curve as JSON (pnp-train --json, run summaries).

#include <nlohmann/json.hpp>
#include <vector>

#include "rl/training_progress.h"

namespace pnp::training {

nlohmann::json curve_json(const std::vector<rl::CurvePoint>& curve);
// {"rollout_s", "update_s", "eval_s", "report_s", "other_s", "total_s"}.
nlohmann::json breakdown_json(const WallBreakdown& breakdown);
nlohmann::json result_json(const rl::TrainingResult& result);

}  // namespace pnp::training
