// pnp-scripted-eval: runs the three scripted experts (or learned checkpoints, --experts) in
// sequence over seeded episodes and prints the success rate and where the failures went
// wrong. Output depends only on the flags (never on --threads or time).

#include <array>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "arm_sim/arm_env_factory.h"
#include "common/error.h"
#include "common/seed_flag.h"
#include "common/validate.h"
#include "nn/checkpoint_io.h"
#include "rl/expert_checkpoint.h"
#include "rl/learned_expert.h"
#include "sim/scripted_evaluation.h"
#include "sim/world_model.h"
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
  return {{"world", world_profile_name(r.world)},
          {"actuation", actuation_name(r.actuation)},
          {"robot", robot_name(r.robot)},
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
          {"failed_in_subtask", r.failed_in_subtask},
          {"failed_after_all_done", r.failed_after_all_done},
          {"failed_episodes", r.failed_episodes}};
}

void print_cell(const pnp::sim::ScriptedEvalReport& r) {
  std::printf("world %s (%s), robot %s, object %s, seed %llu, %d episodes\n",
              std::string(pnp::sim::world_profile_name(r.world)).c_str(),
              std::string(pnp::sim::actuation_name(r.actuation)).c_str(),
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
  std::printf("  failures: in approach %d, manipulate %d, retract %d, after all done %d\n",
              r.failed_in_subtask[0], r.failed_in_subtask[1], r.failed_in_subtask[2],
              r.failed_after_all_done);
}

void print_summary_table(const std::vector<pnp::sim::ScriptedEvalReport>& reports) {
  std::printf("%-6s %-6s %-7s %-12s %9s %9s %15s %13s %7s\n", "world", "hand", "robot", "object",
              "episodes", "success", "95% CI", "active steps", "faults");
  for (const auto& r : reports) {
    std::printf("%-6s %-6s %-7s %-12s %9d %9.3f    %.3f-%.3f %7.1f +- %3.1f %7d\n",
                std::string(pnp::sim::world_profile_name(r.world)).c_str(),
                std::string(pnp::sim::actuation_name(r.actuation)).c_str(),
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

// --experts: three comma-separated entries, each a checkpoint path or "scripted".
std::vector<std::unique_ptr<pnp::sim::SubtaskPolicy>> load_experts(const std::string& list) {
  using namespace pnp;
  std::vector<std::string> entries;
  std::size_t begin = 0;
  for (std::size_t comma; (comma = list.find(',', begin)) != std::string::npos; begin = comma + 1)
    entries.push_back(list.substr(begin, comma - begin));
  entries.push_back(list.substr(begin));
  if (entries.size() != sim::kNumSubtasks)
    throw_invalid_argument("--experts", "three comma-separated checkpoints or \"scripted\"",
                           "\"" + list + "\"");
  std::vector<std::unique_ptr<sim::SubtaskPolicy>> out;
  for (std::size_t k = 0; k < entries.size(); ++k) {
    if (entries[k] == "scripted") {
      out.push_back(std::make_unique<sim::ScriptedPolicy>());
      continue;
    }
    out.push_back(rl::learned_expert_from(rl::load_expert(nn::read_file(entries[k])),
                                          sim::subtask_name(sim::kAllSubtasks[k]),
                                          "--experts[" + std::to_string(k) + "]"));
  }
  return out;
}

// One world to evaluate in.
struct Cell {
  pnp::sim::WorldProfile world;
  pnp::sim::Robot robot;
  pnp::sim::ObjectShape object;
  pnp::sim::Actuation actuation;
  std::unique_ptr<pnp::sim::EnvFactory> envs() const {
    return pnp::arm_sim::make_env_factory(robot, object, world, actuation);
  }
};

// --experts empty: the scripted experts.
pnp::sim::ScriptedEvalReport evaluate(const Cell& cell, const std::string& list, long long episodes,
                                      std::uint64_t seed, std::size_t threads) {
  using namespace pnp;
  const auto experts = load_experts(list.empty() ? "scripted,scripted,scripted" : list);
  ThreadPool pool(threads);
  return sim::evaluate_pipeline(
      *cell.envs(), {experts[0].get(), experts[1].get(), experts[2].get()}, episodes, seed, pool);
}

// Replays episode `index` of the evaluation (same seed derivation) and prints every step.
void trace_episode(const Cell& cell, const std::string& list, std::uint64_t seed, long long index) {
  using namespace pnp;
  const auto experts = load_experts(list.empty() ? "scripted,scripted,scripted" : list);
  const auto env = cell.envs()->make();
  const std::uint64_t episode_seed = derive_seed(seed, static_cast<std::uint64_t>(index));
  std::printf(
      "episode %lld (seed %llu): step subtask | action xyz grip | gripper | object | "
      "finger gap | object to goal\n",
      index, static_cast<unsigned long long>(episode_seed));
  const auto outcome = sim::run_pipeline_episode(
      *env, {experts[0].get(), experts[1].get(), experts[2].get()}, episode_seed,
      [](int step, std::optional<sim::Subtask> acting, const sim::Action& a,
         const sim::TaskState& s) {
        std::printf(
            "%2d %-10s | %+.2f %+.2f %+.2f %+.2f | %.3f %.3f %.3f | %.3f %.3f %.3f | %.4f | "
            "%.3f\n",
            step, acting ? std::string(sim::subtask_name(*acting)).c_str() : "idle", a[0], a[1],
            a[2], a[3], s.gripper.x(), s.gripper.y(), s.gripper.z(), s.object.x(), s.object.y(),
            s.object.z(), s.finger_gap_m, (s.object - s.episode_goal).norm());
      });
  std::printf("success %d, physics fault %s, final distance %.3f m\n", outcome.success ? 1 : 0,
              std::string(sim::physics_fault_name(outcome.fault)).c_str(),
              outcome.final_distance_m);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Evaluate the scripted approach -> manipulate -> retract pipeline",
               "pnp-scripted-eval"};
  std::string world(pnp::sim::world_profile_name(pnp::sim::kDefaultWorldProfile));
  std::string robot = "fetch";
  std::string object = "block";
  std::string actuation = "default";
  long long episodes = 100;
  std::uint64_t seed = 0;
  std::size_t threads = 0;
  bool json = false;
  std::string experts;
  long long trace = -1;
  app.add_option("--trace", trace, "print every step of this episode index instead of evaluating");
  app.add_option("--experts", experts,
                 "approach,manipulate,retract: checkpoint paths or \"scripted\" (default: all "
                 "scripted)");
  app.add_option("--world", world, "world profile: paper, gym or all (docs/SIMULATION.md)")
      ->capture_default_str();
  app.add_option("--robot", robot, "fetch, panda or all")->capture_default_str();
  app.add_option("--actuation", actuation,
                 "how the hand follows actions: mocap, arm (the Panda only), all, or default "
                 "(each robot's own: docs/SIMULATION.md)")
      ->capture_default_str();
  app.add_option("--object", object, "block, small_block, cylinder or all")->capture_default_str();
  app.add_option("--episodes", episodes, "number of evaluation episodes (> 0)")
      ->capture_default_str();
  app.add_option("--seed", seed, "episode i uses a seed derived from (seed, i)")
      ->check(pnp::seed_value())
      ->capture_default_str();
  app.add_option("--threads", threads, "worker threads (0: all cores); never changes results")
      ->capture_default_str();
  app.add_flag("--json", json, "print one JSON object");
  return pnp::tools::run_tool(app, argc, argv, [&] {
    pnp::require_positive(episodes, "--episodes");
    const auto worlds =
        select(world, pnp::sim::kAllWorldProfiles, &pnp::sim::parse_world_profile, "--world");
    const auto robots = select(robot, pnp::sim::kAllRobots, &pnp::sim::parse_robot, "--robot");
    const auto objects =
        select(object, pnp::sim::kAllObjectShapes, &pnp::sim::parse_object, "--object");
    std::vector<Cell> cells;
    for (auto w : worlds) {
      for (auto r : robots) {
        // "default": the robot's own; "all": every actuation the robot has.
        std::vector<pnp::sim::Actuation> hands;
        if (actuation == "default") {
          hands = {pnp::sim::default_actuation(r)};
        } else if (actuation == "all") {
          for (auto a : pnp::sim::kAllActuations) {
            if (a == pnp::sim::Actuation::kMocap || r == pnp::sim::Robot::kPanda)
              hands.push_back(a);
          }
        } else {
          hands = {pnp::sim::parse_actuation(actuation, "--actuation")};
          pnp::sim::require_supported(r, hands.front(), "--actuation");
        }
        for (auto o : objects) {
          for (auto a : hands) cells.push_back({w, r, o, a});
        }
      }
    }
    if (trace >= 0) {
      if (cells.size() != 1)
        pnp::throw_invalid_argument("--trace", "one --world, --robot, --object and --actuation",
                                    "\"all\"");
      trace_episode(cells.front(), experts, seed, trace);
      return;
    }
    std::vector<pnp::sim::ScriptedEvalReport> reports;
    for (const Cell& cell : cells)
      reports.push_back(evaluate(cell, experts, episodes, seed, threads));
    if (reports.size() == 1) {
      if (json) {
        std::cout << to_json(reports.front()).dump() << "\n";
      } else {
        print_cell(reports.front());
      }
      return;
    }
    if (json) {
      nlohmann::json out = nlohmann::json::array();
      for (const auto& r : reports) out.push_back(to_json(r));
      std::cout << nlohmann::json{{"cells", out}}.dump() << "\n";
    } else {
      print_summary_table(reports);
    }
  });
}
