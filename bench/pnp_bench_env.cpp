// pnp-bench-env: environment steps per second, against the physics floor measured in the
// same run: the same mj_step calls on the same model, replaying the exact inputs (mocap
// target, finger controls, gravity compensation) that the environment applied, so both
// loops simulate identical trajectories. overhead_ratio = env time / raw physics time.
// For the Panda, the arm-actuated world's steps per second too (the same scripted
// episodes, the hand moved by the arm's controller at 1 kHz), and what it costs against
// the mocap world in the same run (arm_vs_mocap_time_ratio).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "arm_sim/arm_actuated_env.h"
#include "common/rng.h"
#include "common/seed_flag.h"
#include "common/validate.h"
#include "sim/scripted_expert.h"
#include "sim/subtask_sequence.h"
#include "sim/vec_env.h"
#include "sim/world_layout.h"
#include "tools/common/cli.h"

namespace {

using Clock = std::chrono::steady_clock;
using namespace pnp::sim;

// The inputs MuJoCo saw during one environment step.
struct StepInputs {
  std::vector<mjtNum> mocap_pos, ctrl, qfrc_applied;
};
struct EpisodeRecord {
  std::vector<mjtNum> qpos, qvel, mocap_pos, mocap_quat;
  StepInputs start;
  std::vector<StepInputs> steps;
  std::vector<mjtNum> final_qpos;
};

StepInputs capture_inputs(const mjModel* m, const mjData* d) {
  return {{d->mocap_pos, d->mocap_pos + 3 * m->nmocap},
          {d->ctrl, d->ctrl + m->nu},
          {d->qfrc_applied, d->qfrc_applied + m->nv}};
}

// The scripted action for env's current state in the fixed subtask sequence.
Action scripted_step_action(const SubtaskSequence& sequence, const PickPlaceEnv& env) {
  return sequence.idle() ? idle_action() : scripted_action(sequence.current(), env.task_state());
}

// Runs `episodes` scripted episodes; returns the seconds spent inside env.step().
double time_env(PickPlaceEnv& env, int episodes, std::uint64_t seed,
                std::vector<EpisodeRecord>* log) {
  double seconds = 0;
  const mjModel* m = env.mj_model();
  for (int e = 0; e < episodes; ++e) {
    env.reset(pnp::derive_seed(seed, static_cast<std::uint64_t>(e)));
    EpisodeRecord record;
    if (log) {
      const mjData* d = env.mj_data();
      record = {{d->qpos, d->qpos + m->nq},
                {d->qvel, d->qvel + m->nv},
                {d->mocap_pos, d->mocap_pos + 3 * m->nmocap},
                {d->mocap_quat, d->mocap_quat + 4 * m->nmocap},
                capture_inputs(m, d),
                {},
                {}};
    }
    SubtaskSequence sequence(env.episode_steps());
    while (!env.needs_reset()) {
      const Action a = scripted_step_action(sequence, env);
      const Goal g = env.objective_goal(sequence.objective());
      const auto t0 = Clock::now();
      const StepResult r = env.step(a, g, sequence.objective());
      seconds += std::chrono::duration<double>(Clock::now() - t0).count();
      sequence.record_step(r.objective_done);
      if (log) record.steps.push_back(capture_inputs(m, env.mj_data()));
    }
    if (log) {
      record.final_qpos.assign(env.mj_data()->qpos, env.mj_data()->qpos + m->nq);
      log->push_back(std::move(record));
    }
  }
  return seconds;
}

// Runs `episodes` scripted episodes on any environment; returns the seconds inside step().
// Seconds per step of scripted episodes (per step: the arm's episodes are longer).
double time_any_env(Environment& env, int episodes, std::uint64_t seed) {
  double seconds = 0;
  long long steps = 0;
  for (int e = 0; e < episodes; ++e) {
    env.reset(pnp::derive_seed(seed, static_cast<std::uint64_t>(e)));
    SubtaskSequence sequence(env.episode_steps());
    while (!env.needs_reset()) {
      const TaskState state = env.task_state();
      const Action a = sequence.idle() ? idle_action() : scripted_action(sequence.current(), state);
      const Goal g = objective_goal(sequence.objective(), state);
      const auto t0 = Clock::now();
      const StepResult r = env.step(a, g, sequence.objective());
      seconds += std::chrono::duration<double>(Clock::now() - t0).count();
      ++steps;
      sequence.record_step(r.objective_done);
    }
  }
  return seconds / static_cast<double>(steps);
}

// Replays the recorded inputs with bare mj_step; returns the seconds of the step loops.
double time_raw_physics(const mjModel* m, mjData* d, const std::vector<EpisodeRecord>& log,
                        double& max_qpos_deviation) {
  double seconds = 0;
  for (const EpisodeRecord& rec : log) {
    mj_resetData(m, d);
    std::copy(rec.qpos.begin(), rec.qpos.end(), d->qpos);
    std::copy(rec.qvel.begin(), rec.qvel.end(), d->qvel);
    std::copy(rec.mocap_pos.begin(), rec.mocap_pos.end(), d->mocap_pos);
    std::copy(rec.mocap_quat.begin(), rec.mocap_quat.end(), d->mocap_quat);
    // The start controls matter: mj_forward's solver result seeds the next warm start.
    std::copy(rec.start.ctrl.begin(), rec.start.ctrl.end(), d->ctrl);
    mj_forward(m, d);  // as reset() does
    const auto t0 = Clock::now();
    for (const StepInputs& in : rec.steps) {
      std::copy(in.mocap_pos.begin(), in.mocap_pos.end(), d->mocap_pos);
      std::copy(in.ctrl.begin(), in.ctrl.end(), d->ctrl);
      std::copy(in.qfrc_applied.begin(), in.qfrc_applied.end(), d->qfrc_applied);
      for (int k = 0; k < pnp::sim::layout::kSubstepsPerStep; ++k) mj_step(m, d);
    }
    seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    for (int i = 0; i < m->nq; ++i) {
      max_qpos_deviation = std::max(
          max_qpos_deviation, std::abs(rec.final_qpos[static_cast<std::size_t>(i)] - d->qpos[i]));
    }
  }
  return seconds;
}

// All threads: one environment per pool thread, stepped as a batch.
double time_vec_env(VecEnv& vec, int steps_per_env, std::uint64_t seed) {
  const std::size_t n = vec.size();
  std::vector<double> actions(n * kActionSize), goals(n * kGoalSize);
  std::vector<Objective> objectives(n);
  std::vector<StepResult> results(n);
  std::vector<SubtaskSequence> sequences(n, SubtaskSequence(layout::kEpisodeSteps));
  vec.reset(seed);
  double seconds = 0;
  for (int t = 0; t < steps_per_env; ++t) {
    for (std::size_t i = 0; i < n; ++i) {
      if (vec.env(i).needs_reset()) sequences[i] = SubtaskSequence(vec.env(i).episode_steps());
      const Action a = scripted_step_action(sequences[i], vec.env(i));
      const Goal g = vec.env(i).objective_goal(sequences[i].objective());
      std::copy(a.data(), a.data() + kActionSize, actions.data() + i * kActionSize);
      std::copy(g.data(), g.data() + kGoalSize, goals.data() + i * kGoalSize);
      objectives[i] = sequences[i].objective();
    }
    const auto t0 = Clock::now();
    vec.step(actions, goals, objectives, results);
    seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    for (std::size_t i = 0; i < n; ++i) sequences[i].record_step(results[i].objective_done);
  }
  return seconds;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Benchmark environment steps per second against raw MuJoCo physics",
               "pnp-bench-env"};
  std::string robot = "fetch", object = "block";
  std::string world_name{pnp::sim::world_profile_name(pnp::sim::kDefaultWorldProfile)};
  int episodes = 20, rounds = 5;
  std::size_t threads = 0;
  std::uint64_t seed = 1;
  bool json = false;
  app.add_option("--robot", robot)->capture_default_str();
  app.add_option("--object", object)->capture_default_str();
  app.add_option("--world", world_name, "world profile: paper or gym")->capture_default_str();
  app.add_option("--episodes", episodes, "episodes per round (50 steps each)")
      ->capture_default_str();
  app.add_option("--rounds", rounds, "alternating env/raw rounds; the best round counts")
      ->capture_default_str();
  app.add_option("--threads", threads, "threads for the all-threads figure (0: all cores)");
  app.add_option("--seed", seed)->check(pnp::seed_value())->capture_default_str();
  app.add_flag("--json", json, "print one JSON object");
  return pnp::tools::run_tool(app, argc, argv, [&] {
    pnp::require_positive(episodes, "--episodes");
    pnp::require_positive(rounds, "--rounds");
    const auto world =
        WorldModel::load(parse_robot(robot, "--robot"), parse_object(object, "--object"),
                         pnp::sim::parse_world_profile(world_name, "--world"));
    PickPlaceEnv env(world);
    pnp::sim::DataPtr raw = pnp::sim::make_data(world->mj());
    double best_env = 1e300, best_raw = 1e300;
    // The replay reproduces the environment's trajectories up to rounding (the env's
    // observation pass reorders a few floating-point operations, and contact amplifies
    // that): the workloads are the same if the final states agree to well under 1 mm.
    double max_qpos_deviation = 0;
    for (int r = 0; r < rounds; ++r) {
      std::vector<EpisodeRecord> log;
      time_env(env, episodes, seed, &log);  // records the inputs (untimed pass)
      best_env = std::min(best_env, time_env(env, episodes, seed, nullptr));
      best_raw =
          std::min(best_raw, time_raw_physics(world->mj(), raw.get(), log, max_qpos_deviation));
    }
    const double steps = static_cast<double>(episodes) * pnp::sim::layout::kEpisodeSteps;
    // The arm-actuated world, alternating with the mocap one so both see the same machine.
    std::optional<double> best_arm;
    if (world->robot() == Robot::kPanda) {
      pnp::arm_sim::ArmActuatedEnv arm(world);
      for (int r = 0; r < rounds; ++r) {
        const double mocap_step_s = time_any_env(env, episodes, seed);
        const double arm_step_s = time_any_env(arm, episodes, seed);
        best_env = std::min(best_env, mocap_step_s * steps);
        best_arm = std::min(best_arm.value_or(1e300), arm_step_s);
      }
    }

    VecEnv vec(world, 1, threads);
    VecEnv vec_all(world, static_cast<long long>(vec.threads()), vec.threads());
    const int steps_per_env = episodes * pnp::sim::layout::kEpisodeSteps;
    double best_vec = 1e300;
    for (int r = 0; r < rounds; ++r)
      best_vec = std::min(best_vec, time_vec_env(vec_all, steps_per_env, seed));
    const double vec_steps =
        static_cast<double>(steps_per_env) * static_cast<double>(vec_all.size());

    nlohmann::json out = {
        {"robot", robot},
        {"object", object},
        {"world", world_name},
        {"seed", seed},
        {"episodes_per_round", episodes},
        {"rounds", rounds},
        {"threads", vec_all.threads()},
        {"env_steps_per_s", steps / best_env},
        {"env_steps_per_s_all_threads", vec_steps / best_vec},
        {"physics_floor_steps_per_s", steps / best_raw},
        {"mj_step_per_s", steps * pnp::sim::layout::kSubstepsPerStep / best_raw},
        {"overhead_ratio", best_env / best_raw},
        {"thread_scaling", (vec_steps / best_vec) / (steps / best_env)},
        {"replay_max_qpos_deviation", max_qpos_deviation},
        {"replay_same_trajectory_within_1mm", max_qpos_deviation < 1e-3},
    };
    if (best_arm) {
      out["arm_env_steps_per_s"] = 1 / *best_arm;
      out["arm_vs_mocap_time_ratio"] = *best_arm * steps / best_env;  // per step
    }
    if (json) {
      std::cout << out.dump() << "\n";
    } else {
      std::cout << out.dump(2) << "\n";
    }
  });
}
