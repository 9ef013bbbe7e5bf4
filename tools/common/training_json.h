#pragma once
// JSON and progress lines for training results, shared by the training tools.

#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "rl/ddpg_her_config.h"
#include "rl/training_progress.h"

namespace pnp::tools {

nlohmann::json curve_json(const std::vector<rl::CurvePoint>& curve);
nlohmann::json result_json(const rl::TrainingResult& result);
nlohmann::json ddpg_config_json(const rl::DdpgHerConfig& c);
void print_progress(std::FILE* out, const std::string& role, const rl::CurvePoint& p);

}  // namespace pnp::tools
