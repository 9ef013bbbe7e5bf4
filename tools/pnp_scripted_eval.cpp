// pnp-scripted-eval: runs the three scripted experts in sequence over seeded episodes and
// prints the success rate. Output depends only on the flags (never on --threads or time).

#include <array>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/validate.h"
#include "sim/scripted_evaluation.h"
#include "tools/common/cli.h"

namespace {

nlohmann::json to_json(const pnp::sim::ScriptedEvalReport& r) {
  using namespace pnp::sim;
  nlohmann::json subtasks = nlohmann::json::object();
  for (Subtask s : kAllSubtasks) {
    const auto k = static_cast<std::size_t>(s);
    subtasks[std::string(subtask_name(s))] = {{"success_rate", r.subtask_success_rate[k]},
                                              {"mean_steps", r.subtask_mean_steps[k]}};
  }
  return {{"robot", robot_name(r.robot)},
          {"object", object_name(r.object)},
          {"seed", r.seed},
          {"episodes", r.episodes},
          {"success_rate", r.success_rate},
          {"success_ci95", {r.success_ci95_low, r.success_ci95_high}},
          {"mean_steps", r.mean_steps},
          {"std_steps", r.std_steps},
          {"env_steps", r.env_steps},
          {"mean_final_distance_m", r.mean_final_distance_m},
          {"physics_faults", r.physics_faults},
          {"subtasks", subtasks},
          {"failed_episodes", r.failed_episodes}};
}

void print_cell(const pnp::sim::ScriptedEvalReport& r) {
  std::printf("robot %s, object %s, seed %llu, %d episodes\n",
              std::string(pnp::sim::robot_name(r.robot)).c_str(),
              std::string(pnp::sim::object_name(r.object)).c_str(),
              static_cast<unsigned long long>(r.seed), r.episodes);
  std::printf("  success rate   %.3f  (95%% CI %.3f-%.3f)\n", r.success_rate, r.success_ci95_low,
              r.success_ci95_high);
  std::printf("  active steps   %.1f +- %.1f of 50\n", r.mean_steps, r.std_steps);
  for (auto s : pnp::sim::kAllSubtasks) {
    const auto k = static_cast<std::size_t>(s);
    std::printf("  %-10s     done %.3f in %.1f steps\n",
                std::string(pnp::sim::subtask_name(s)).c_str(), r.subtask_success_rate[k],
                r.subtask_mean_steps[k]);
  }
  std::printf("  physics faults %d\n", r.physics_faults);
}

void print_summary_table(const std::vector<pnp::sim::ScriptedEvalReport>& reports) {
  std::printf("%-7s %-12s %9s %9s %15s %13s %7s\n", "robot", "object", "episodes", "success",
              "95% CI", "active steps", "faults");
  for (const auto& r : reports) {
    std::printf("%-7s %-12s %9d %9.3f    %.3f-%.3f %7.1f +- %3.1f %7d\n",
                std::string(pnp::sim::robot_name(r.robot)).c_str(),
                std::string(pnp::sim::object_name(r.object)).c_str(), r.episodes, r.success_rate,
                r.success_ci95_low, r.success_ci95_high, r.mean_steps, r.std_steps,
                r.physics_faults);
  }
}

template <typename T, std::size_t N>
std::vector<T> select(const std::string& name, const std::array<T, N>& all,
                      T (*parse)(std::string_view, std::string_view), const char* field) {
  if (name == "all") return {all.begin(), all.end()};
  return {parse(name, field)};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Evaluate the scripted approach -> manipulate -> retract pipeline",
               "pnp-scripted-eval"};
  std::string robot = "fetch";
  std::string object = "block";
  long long episodes = 100;
  std::uint64_t seed = 0;
  std::size_t threads = 0;
  bool json = false;
  app.add_option("--robot", robot, "fetch, panda or all")->capture_default_str();
  app.add_option("--object", object, "block, small_block, cylinder or all")->capture_default_str();
  app.add_option("--episodes", episodes, "number of evaluation episodes (> 0)")
      ->capture_default_str();
  app.add_option("--seed", seed, "episode i uses a seed derived from (seed, i)")
      ->capture_default_str();
  app.add_option("--threads", threads, "worker threads (0: all cores); never changes results")
      ->capture_default_str();
  app.add_flag("--json", json, "print one JSON object");
  return pnp::tools::run_tool(app, argc, argv, [&] {
    pnp::require_positive(episodes, "--episodes");
    const auto robots = select(robot, pnp::sim::kAllRobots, &pnp::sim::parse_robot, "--robot");
    const auto objects =
        select(object, pnp::sim::kAllObjectShapes, &pnp::sim::parse_object, "--object");
    std::vector<pnp::sim::ScriptedEvalReport> reports;
    for (auto r : robots) {
      for (auto o : objects)
        reports.push_back(pnp::sim::evaluate_scripted(r, o, episodes, seed, threads));
    }
    if (reports.size() == 1) {
      if (json) {
        std::cout << to_json(reports.front()).dump() << "\n";
      } else {
        print_cell(reports.front());
      }
      return;
    }
    if (json) {
      nlohmann::json cells = nlohmann::json::array();
      for (const auto& r : reports) cells.push_back(to_json(r));
      std::cout << nlohmann::json{{"cells", cells}}.dump() << "\n";
    } else {
      print_summary_table(reports);
    }
  });
}
