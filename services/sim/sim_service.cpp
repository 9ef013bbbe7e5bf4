#include "services/sim/sim_service.h"

#include <cmath>
#include <limits>

#include "common/error.h"
#include "services/common/access_control.h"
#include "services/common/convert.h"
#include "services/common/sim_convert.h"
#include "services/common/status.h"
#include "services/common/time_convert.h"
#include "sim/world_layout.h"

namespace pnp::services {
namespace {

namespace sv1 = pnp::sim::v1;

constexpr int kMaxRewardPairs = 100'000;

std::size_t checked_index(int index, const EnvBatch& batch, const std::string& field) {
  if (index < 0 || static_cast<std::size_t>(index) >= batch.envs.size()) {
    throw_invalid_argument(field, "an index in [0, " + std::to_string(batch.envs.size()) + ")",
                           std::to_string(index));
  }
  return static_cast<std::size_t>(index);
}

void fill_state(const sim::Environment& env, int index, sv1::EnvState& out) {
  out.set_index(index);
  to_proto(env.observation(), *out.mutable_observation());
  to_proto(env.episode_goal(), *out.mutable_episode_goal());
  out.set_elapsed_steps(env.elapsed_steps());
}

sim::Action action_from_proto(const common::v1::Action& a, const std::string& field) {
  const sim::Action out(a.dx(), a.dy(), a.dz(), a.gripper());
  for (int k = 0; k < sim::kActionSize; ++k) {
    if (!std::isfinite(out(k)))
      throw_invalid_argument(field, "finite values", "a non-finite component " + std::to_string(k));
  }
  return out;
}

void fill_spec(sv1::TensorSpec& spec, const std::string& name, int size, double low, double high,
               const std::vector<std::string>& units) {
  spec.set_name(name);
  spec.set_size(size);
  for (int k = 0; k < size; ++k) {
    spec.add_low(low);
    spec.add_high(high);
    spec.add_units(units[static_cast<std::size_t>(k)]);
  }
}

}  // namespace

void reset_batch(EnvBatch& batch, const sv1::ResetRequest& request, sv1::ResetResponse& response) {
  std::vector<std::size_t> indices;
  for (int i = 0; i < request.indices_size(); ++i)
    indices.push_back(
        checked_index(request.indices(i), batch, "indices[" + std::to_string(i) + "]"));
  if (indices.empty())
    for (std::size_t k = 0; k < batch.envs.size(); ++k) indices.push_back(k);
  const auto seeds = request.episode_seeds();
  if (!seeds.empty() && static_cast<std::size_t>(seeds.size()) != indices.size()) {
    throw_invalid_argument(
        "episode_seeds",
        "none, or one per environment reset (" + std::to_string(indices.size()) + ")",
        std::to_string(seeds.size()) + " seeds");
  }
  for (std::size_t i = 0; i < indices.size(); ++i) {
    const std::size_t k = indices[i];
    if (seeds.empty()) {
      batch.reset(k);
    } else {
      batch.reset(k, seeds[static_cast<int>(i)]);
    }
    fill_state(*batch.envs[k], static_cast<int>(k), *response.add_states());
  }
}

void step_batch(EnvBatch& batch, const sv1::StepRequest& request, sv1::StepResponse& response) {
  struct Planned {
    std::size_t index;
    sim::Action action;
    sim::Goal goal;
    sim::Objective objective;
  };
  std::vector<Planned> plan;
  std::vector<bool> seen(batch.envs.size(), false);
  for (int i = 0; i < request.actions_size(); ++i) {
    const auto& a = request.actions(i);
    const std::string field = "actions[" + std::to_string(i) + "]";
    const std::size_t k = checked_index(a.index(), batch, field + ".index");
    if (seen[k])
      throw_invalid_argument(field + ".index", "each environment at most once",
                             std::to_string(k) + " again");
    seen[k] = true;
    if (batch.envs[k]->needs_reset()) {
      throw Error(ErrorCode::kFailedPrecondition,
                  field + ": environment " + std::to_string(k) +
                      " has no episode running (its 50 steps are over or it was never reset): "
                      "Reset it first");
    }
    plan.push_back({k, action_from_proto(a.action(), field + ".action"),
                    from_proto(a.goal(), field + ".goal"),
                    from_proto(a.objective(), field + ".objective")});
  }
  for (const Planned& p : plan) {  // everything validated: now move
    const sim::StepResult r = batch.envs[p.index]->step(p.action, p.goal, p.objective);
    auto* out = response.add_results();
    fill_state(*batch.envs[p.index], static_cast<int>(p.index), *out->mutable_state());
    out->set_reward(r.reward);
    out->set_objective_done(r.objective_done);
    out->set_task_success(r.task_success);
    out->set_episode_over(r.episode_over);
    out->set_fault(to_proto(r.fault));
  }
}

SimServiceImpl::SimServiceImpl(MetricsRegistry* metrics, StreamLimits* limits)
    : env_steps_(metrics ? &metrics->counter("pnp_env_steps_total",
                                             "Environment steps executed (Step and StreamRollout).")
                         : nullptr),
      limits_(limits) {}

void SimServiceImpl::count_steps(const sv1::StepResponse& response) {
  if (env_steps_) env_steps_->Increment(response.results_size());
}

grpc::Status SimServiceImpl::CreateEnv(grpc::ServerContext* context,
                                       const sv1::CreateEnvRequest* request,
                                       sv1::CreateEnvResponse* response) {
  return guarded([&] {
    const auto robot = from_proto(request->robot(), "robot");
    const auto object = from_proto(request->object(), "object");
    const auto world = from_proto(request->world(), "world");
    const auto actuation = from_proto(request->actuation(), robot, "actuation");
    std::chrono::steady_clock::duration timeout = std::chrono::seconds(300);
    if (request->has_idle_timeout())
      timeout = from_proto(request->idle_timeout(), "idle_timeout", EnvRegistry::kMaxIdleTimeout);
    response->set_env_id(registry_.create(robot, object, world, actuation, request->seed(),
                                          request->count(), timeout, principal_of(*context)));
    response->set_count(request->count());
    response->set_episode_steps(sim::episode_steps(actuation));
    return grpc::Status::OK;
  });
}

grpc::Status SimServiceImpl::Reset(grpc::ServerContext* context, const sv1::ResetRequest* request,
                                   sv1::ResetResponse* response) {
  return guarded([&] {
    const auto batch = registry_.get(request->env_id(), principal_of(*context));
    std::lock_guard lock(batch->mutex);
    reset_batch(*batch, *request, *response);
    return grpc::Status::OK;
  });
}

grpc::Status SimServiceImpl::Step(grpc::ServerContext* context, const sv1::StepRequest* request,
                                  sv1::StepResponse* response) {
  return guarded([&] {
    const auto batch = registry_.get(request->env_id(), principal_of(*context));
    std::lock_guard lock(batch->mutex);
    step_batch(*batch, *request, *response);
    count_steps(*response);
    return grpc::Status::OK;
  });
}

grpc::Status SimServiceImpl::ComputeReward(grpc::ServerContext*,
                                           const sv1::ComputeRewardRequest* request,
                                           sv1::ComputeRewardResponse* response) {
  return guarded([&] {
    if (request->achieved_size() != request->goals_size()) {
      throw_invalid_argument("goals",
                             std::to_string(request->achieved_size()) + " goals (one per achieved)",
                             std::to_string(request->goals_size()));
    }
    if (request->achieved_size() > kMaxRewardPairs) {
      throw Error(ErrorCode::kResourceExhausted,
                  "achieved: at most " + std::to_string(kMaxRewardPairs) + " pairs per call, got " +
                      std::to_string(request->achieved_size()));
    }
    for (int i = 0; i < request->achieved_size(); ++i) {
      const auto achieved = from_proto(request->achieved(i), "achieved[" + std::to_string(i) + "]");
      const auto goal = from_proto(request->goals(i), "goals[" + std::to_string(i) + "]");
      response->add_rewards(sim::compute_reward(achieved, goal));
    }
    return grpc::Status::OK;
  });
}

grpc::Status SimServiceImpl::GetEnvSpec(grpc::ServerContext*, const sv1::GetEnvSpecRequest* request,
                                        sv1::GetEnvSpecResponse* response) {
  return guarded([&] {
    const sim::Robot robot = from_proto(request->robot(), "robot");
    from_proto(request->object(), "object");
    from_proto(request->world(), "world");
    const sim::Actuation actuation = from_proto(request->actuation(), robot, "actuation");
    const double inf = std::numeric_limits<double>::infinity();
    std::vector<std::string> obs_units;
    for (int k = 0; k < sim::kObservationSize; ++k) {
      obs_units.push_back(k <= 10   ? "m"
                          : k <= 13 ? "rad"
                          : k <= 16 ? "m per step"
                          : k <= 19 ? "rad per step"
                                    : "m per step");
    }
    fill_spec(*response->mutable_observation(), "observation", sim::kObservationSize, -inf, inf,
              obs_units);
    fill_spec(*response->mutable_goal(), "goal", sim::kGoalSize, -inf, inf, {"m", "m", "m"});
    fill_spec(*response->mutable_action(), "action", sim::kActionSize, -1, 1,
              {"0.05 m", "0.05 m", "0.05 m", "finger range"});
    response->set_episode_steps(sim::episode_steps(actuation));
    response->set_step_s(sim::layout::kStepDuration_s);
    response->set_success_distance_m(sim::layout::kTaskSuccessDistance);
    return grpc::Status::OK;
  });
}

grpc::Status SimServiceImpl::CloseEnv(grpc::ServerContext* context,
                                      const sv1::CloseEnvRequest* request, sv1::CloseEnvResponse*) {
  return guarded([&] {
    registry_.close(request->env_id(), principal_of(*context));
    return grpc::Status::OK;
  });
}

grpc::Status SimServiceImpl::StreamRollout(
    grpc::ServerContext* context,
    grpc::ServerReaderWriter<sv1::StreamRolloutResponse, sv1::StreamRolloutRequest>* stream) {
  return guarded([&] {
    auto slot = admit_stream(limits_, *context, "StreamRollout");
    sv1::StreamRolloutRequest request;
    if (!stream->Read(&request)) return grpc::Status::OK;
    slot.touch();
    if (request.request_case() != sv1::StreamRolloutRequest::kEnvId) {
      throw_invalid_argument("env_id", "the first message of a rollout stream to name the batch",
                             "a reset or step");
    }
    const auto batch = registry_.get(request.env_id(), principal_of(*context));
    sv1::StreamRolloutResponse response;
    while (!context->IsCancelled() && stream->Read(&request)) {
      slot.touch();
      response.Clear();
      {
        std::lock_guard lock(batch->mutex);
        batch->touch();
        if (request.has_reset()) {
          reset_batch(*batch, request.reset(), *response.mutable_reset());
        } else if (request.has_step()) {
          step_batch(*batch, request.step(), *response.mutable_step());
          count_steps(response.step());
        } else {
          throw_invalid_argument("request", "a reset or a step", "another env_id");
        }
      }
      if (!stream->Write(response)) break;
    }
    return grpc::Status::OK;
  });
}

}  // namespace pnp::services
