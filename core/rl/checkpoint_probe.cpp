#include "rl/checkpoint_probe.h"

#include <cmath>
#include <memory>
#include <string>

#include "common/error.h"
#include "rl/choreographer_checkpoint.h"
#include "rl/ddpg_her_agent.h"
#include "rl/expert_checkpoint.h"
#include "rl/hierarchy_controller.h"
#include "sim/subtask_policy.h"
#include "sim/world_layout.h"

namespace pnp::rl {
namespace {

namespace layout = sim::layout;

// A state over the table (the gripper above the object, the goal in the air): the
// normalisers see values of the usual size.
sim::Observation probe_observation() {
  sim::Observation o = sim::Observation::Zero();
  o.head<3>() << layout::kTableCenter_x, layout::kTableCenter_y, layout::kTableTop_z + 0.1;
  o.segment<3>(sim::obs::kObjectPos) << layout::kTableCenter_x, layout::kTableCenter_y,
      layout::kTableTop_z + 0.025;
  o.segment<3>(sim::obs::kObjectRelPos) = o.segment<3>(sim::obs::kObjectPos) - o.head<3>();
  return o;
}

sim::Goal probe_goal() {
  return {layout::kTableCenter_x, layout::kTableCenter_y, layout::kTableTop_z + 0.15};
}

bool all_finite(std::span<const double> values) {
  for (double v : values)
    if (!std::isfinite(v)) return false;
  return true;
}

void require_finite(bool finite, const std::string& what) {
  if (!finite) throw_invalid_argument(what, "finite outputs on a probe input", "non-finite ones");
}

void probe_expert(std::string_view role, std::span<const std::uint8_t> bytes) {
  const LoadedExpert expert = load_expert(bytes);
  if (expert.meta.role != role) {
    throw_invalid_argument("role", "a checkpoint of role " + std::string(role),
                           "role " + expert.meta.role);
  }
  ActorSnapshot actor(expert.actor, expert.observation_normalizer, expert.goal_normalizer,
                      expert.meta.clip_obs);
  const sim::Action a = actor.act(probe_observation(), probe_goal());
  require_finite(all_finite({a.data(), static_cast<std::size_t>(a.size())}), "actor");
}

void probe_choreographer(std::span<const std::uint8_t> bytes) {
  LoadedChoreographer loaded = load_choreographer(bytes);
  HierarchyController::Experts experts{std::make_unique<sim::ScriptedPolicy>(),
                                       std::make_unique<sim::ScriptedPolicy>(),
                                       std::make_unique<sim::ScriptedPolicy>()};
  HierarchyController controller(std::move(loaded.net), std::move(experts), 0.05,
                                 sim::layout::kEpisodeSteps);
  const HierarchyController::Decision d = controller.act(probe_observation(), probe_goal());
  require_finite(std::isfinite(d.value) && all_finite(d.probabilities), "network");
}

}  // namespace

void probe_checkpoint(std::string_view role, std::span<const std::uint8_t> bytes,
                      std::string_view field) {
  try {
    if (role == "hlc") {
      probe_choreographer(bytes);
    } else {
      probe_expert(role, bytes);
    }
  } catch (const Error& e) {
    throw Error(e.code(), std::string(field) + ": " + e.what());
  }
}

}  // namespace pnp::rl
