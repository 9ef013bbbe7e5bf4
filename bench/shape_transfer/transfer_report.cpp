#include "bench/shape_transfer/transfer_report.h"

#include <fmt/format.h>

#include "training/training_json.h"

namespace pnp::bench {
namespace {

std::string rate_cell(const nlohmann::json& cell) {
  if (cell.is_null()) return "-";
  std::string text = fmt::format("{:.3f} ({}/{})", cell.at("success_rate").get<double>(),
                                 cell.at("successes").get<int>(), cell.at("episodes").get<int>());
  if (const auto errors = cell.at("gateway_errors").size(); errors > 0)
    text += fmt::format(", {} refused readings", errors);
  // The same scenes in the arm-actuated world: what the gateway should see.
  if (cell.contains("arm_world")) {
    const nlohmann::json& world = cell.at("arm_world");
    text += fmt::format("; arm world {:.3f}, {} scenes differ",
                        world.at("success_any_step").get<double>(),
                        world.at("disagreements_with_gateway").size());
  }
  return text;
}

// "retract 12.0k (reached), ..." for one shape's fine-tuning.
std::string steps_cell(const nlohmann::json& roles) {
  if (roles.is_null() || roles.empty()) return "- (trained on block)";
  if (roles.is_string())
    return "from " + roles.get<std::string>();  // pnp-shape-transfer --fine-tuned
  std::string text;
  for (const auto& r : roles) {
    if (!text.empty()) text += ", ";
    const bool reached = r.at("reached").get<bool>();
    const long long steps = reached ? r.at("steps_to_target").get<long long>()
                                    : r.at("train_env_steps").get<long long>();
    text += fmt::format("{} {:.1f}k{}", r.at("role").get<std::string>(),
                        static_cast<double>(steps) / 1000.0, reached ? "" : " (cap, not reached)");
  }
  return text;
}

}  // namespace

nlohmann::json training_json(const std::vector<RoleTraining>& log) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& r : log) {
    nlohmann::json j = training::result_json(r.result);
    j["role"] = r.role;
    j["wall_to_target_s"] = rl::wall_to_target(r.result);
    out.push_back(std::move(j));
  }
  return out;
}

std::string transfer_markdown(const std::vector<std::string>& shapes,
                              const std::vector<TransferColumn>& columns,
                              const nlohmann::json& cells, const nlohmann::json& fine_tuning) {
  std::string header = "| shape |", rule = "|---|";
  for (const auto& c : columns) {
    header += " " + c.title + " |";
    rule += "---|";
  }
  std::string md = header + " fine-tuning: env steps to target |\n" + rule + "---|\n";
  for (const auto& shape : shapes) {
    md += "| " + shape + " |";
    for (const auto& c : columns) {
      const nlohmann::json& row = cells.contains(shape) ? cells.at(shape) : nlohmann::json();
      md +=
          " " + rate_cell(row.is_object() && row.contains(c.key) ? row.at(c.key) : nullptr) + " |";
    }
    md += " " + steps_cell(fine_tuning.contains(shape) ? fine_tuning.at(shape) : nullptr) + " |\n";
  }
  return md;
}

}  // namespace pnp::bench
