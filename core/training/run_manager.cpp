#include "training/run_manager.h"

#include <algorithm>
#include <array>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "nn/gemm_path.h"
#include "rl/choreographer_checkpoint.h"
#include "rl/expert_checkpoint.h"
#include "sim/subtask.h"
#include "training/role_training.h"

namespace pnp::training {
namespace {

using Clock = std::chrono::steady_clock;

store::MetricPoint to_metric(const rl::CurvePoint& p) {
  return {p.env_steps,       p.episodes,    p.wall_s,     p.task_success, p.subtask_success,
          p.sampled_success, p.critic_loss, p.actor_loss, p.updates,      p.stop_score};
}

rl::CurvePoint to_curve_point(const store::MetricPoint& m) {
  rl::CurvePoint p;
  p.env_steps = m.env_steps;
  p.episodes = m.episodes;
  p.wall_s = m.wall_s;
  p.task_success = m.task_success;
  p.subtask_success = m.subtask_success;
  p.sampled_success = m.sampled_success;
  p.critic_loss = m.critic_loss;
  p.actor_loss = m.actor_loss;
  p.updates = m.updates;
  p.stop_score = m.stop_score.value_or(0);  // the trainer recomputes it when it resumes
  return p;
}

std::string expert_role(std::size_t k) {
  return std::string(sim::subtask_name(sim::kAllSubtasks[k]));
}

// The stored config: the spec and the checkpoints it starts from, so a resumed run is
// rebuilt exactly.
std::string config_json(const TrainingSpec& spec, const CheckpointRefs& refs) {
  nlohmann::json checkpoints = {{"experts", refs.experts}};
  checkpoints["parent"] = refs.parent ? nlohmann::json(*refs.parent) : nlohmann::json(nullptr);
  return nlohmann::json{{"spec", to_json(spec)}, {"checkpoints", checkpoints}}.dump();
}

std::pair<TrainingSpec, CheckpointRefs> parse_config(const std::string& text) {
  const nlohmann::json j = nlohmann::json::parse(text);
  CheckpointRefs refs;
  const auto& checkpoints = j.at("checkpoints");
  if (!checkpoints.at("parent").is_null())
    refs.parent = checkpoints.at("parent").get<std::int64_t>();
  refs.experts = checkpoints.at("experts").get<std::vector<std::int64_t>>();
  return {spec_from_json(j.at("spec")), refs};
}

// A stored checkpoint, checked to be of `role`.
store::Checkpoint load_of_role(store::RunStore& store, std::int64_t id, const std::string& role,
                               const std::string& field) {
  if (id <= 0) throw_invalid_argument(field, "a positive checkpoint id", std::to_string(id));
  store::Checkpoint c = store.load_checkpoint(id);
  if (c.info.role != role) {
    throw_invalid_argument(field, "a checkpoint of role " + role,
                           "checkpoint " + std::to_string(id) + " of role " + c.info.role);
  }
  return c;
}

// A parent must have the network shape the run will train.
void check_parent_shape(const TrainingSpec& spec, const store::Checkpoint& parent) {
  if (spec.role == "hlc") {
    if (!(rl::load_choreographer(parent.blob).meta.network == spec.a3c.network))
      throw_invalid_argument("parent_checkpoint_id", "a choreographer of the run's network shape",
                             "another shape");
    return;
  }
  const rl::ExpertMeta meta = rl::load_expert(parent.blob).meta;
  if (meta.hidden != spec.ddpg.hidden || meta.hidden_activation != spec.ddpg.hidden_activation) {
    throw_invalid_argument("parent_checkpoint_id",
                           "an expert with the run's hidden widths and activation",
                           "checkpoint " + std::to_string(parent.info.id) + " of another shape");
  }
}

}  // namespace

RunManager::RunManager(const RunManagerOptions& options)
    : options_(options), handler_store_(options.db_path) {
  if (!store::is_known_role(options_.role))
    throw_invalid_argument("role", "one of approach, manipulate, retract, hlc, e2e",
                           "\"" + options_.role + "\"");
  for (store::RunState state : {store::RunState::kRunning, store::RunState::kPending}) {
    store::RunFilter filter;
    filter.role = options_.role;
    filter.state = state;
    filter.limit = 1000;
    for (const auto& run : handler_store_.list_runs(filter)) queue_.push_back(run.id);
  }
  std::sort(queue_.begin(), queue_.end());  // oldest first
  worker_ = std::jthread([this](std::stop_token shutdown) { work(shutdown); });
}

RunManager::~RunManager() = default;  // worker_ requests stop and joins first

store::RunRecord RunManager::create(const TrainingSpec& spec, const CheckpointRefs& given) {
  if (spec.role != options_.role) {
    throw_invalid_argument("role", "\"" + options_.role + "\" (this service's role)",
                           "\"" + spec.role + "\"");
  }
  spec.validate();
  CheckpointRefs refs = given;
  std::lock_guard lock(handler_mutex_);
  if (refs.parent)
    check_parent_shape(
        spec, load_of_role(handler_store_, *refs.parent, spec.role, "parent_checkpoint_id"));
  if (spec.role == "hlc") {
    if (refs.experts.empty()) {
      for (std::size_t k = 0; k < sim::kNumSubtasks; ++k) {
        const auto promoted = handler_store_.promoted(expert_role(k));
        if (!promoted) {
          throw Error(ErrorCode::kFailedPrecondition,
                      "no promoted " + expert_role(k) +
                          " checkpoint: promote one or pass expert_checkpoint_ids");
        }
        refs.experts.push_back(promoted->checkpoint_id);
      }
    }
    if (refs.experts.size() != sim::kNumSubtasks) {
      throw_invalid_argument("expert_checkpoint_ids", "3 ids (approach, manipulate, retract)",
                             std::to_string(refs.experts.size()) + " ids");
    }
  } else if (!refs.experts.empty()) {
    const std::size_t before =
        spec.is_expert() ? static_cast<std::size_t>(sim::parse_subtask(spec.role)) : 0;
    if (refs.experts.size() != before) {
      throw_invalid_argument("prefix_checkpoint_ids",
                             std::to_string(before) + " ids (the experts before " + spec.role + ")",
                             std::to_string(refs.experts.size()) + " ids");
    }
  }
  for (std::size_t k = 0; k < refs.experts.size(); ++k) {
    load_of_role(handler_store_, refs.experts[k], expert_role(k),
                 (spec.role == "hlc" ? "expert_checkpoint_ids[" : "prefix_checkpoint_ids[") +
                     std::to_string(k) + "]");
  }
  store::RunSpec record{spec.role,
                        spec.algorithm,
                        std::string(sim::robot_name(spec.robot)),
                        std::string(sim::object_name(spec.object)),
                        spec.seed,
                        config_json(spec, refs),
                        options_.code_commit,
                        refs.parent,
                        std::string(nn::gemm_path_name(nn::active_gemm_path()))};
  const store::RunRecord run = handler_store_.create_run(record);
  {
    std::lock_guard queue_lock(mutex_);
    queue_.push_back(run.id);
  }
  queue_cv_.notify_all();
  changed();
  return run;
}

store::RunRecord RunManager::cancel(std::int64_t run_id) {
  std::lock_guard lock(handler_mutex_);
  const store::RunRecord run = handler_store_.get_run(run_id);
  if (run.spec.role != options_.role) {
    throw Error(ErrorCode::kFailedPrecondition, "run " + std::to_string(run_id) + " is a " +
                                                    run.spec.role + " run: cancel it on the " +
                                                    run.spec.role + " training service");
  }
  if (store::is_terminal(run.state)) {
    throw Error(ErrorCode::kFailedPrecondition,
                "run " + std::to_string(run_id) + " has already finished (" +
                    std::string(store::run_state_name(run.state)) + ")");
  }
  {
    std::lock_guard queue_lock(mutex_);
    if (active_ && active_->run_id == run_id) {
      active_->cancel_requested = true;
      active_->stop.request_stop();
      return run;  // the worker records CANCELLED when the trainer returns
    }
    std::erase(queue_, run_id);
  }
  const store::RunRecord cancelled = handler_store_.set_state(run_id, store::RunState::kCancelled);
  changed();
  return cancelled;
}

store::RunRecord RunManager::get(std::int64_t run_id) {
  std::lock_guard lock(handler_mutex_);
  return handler_store_.get_run(run_id);
}

std::vector<store::RunRecord> RunManager::list(store::RunFilter filter) {
  filter.role = options_.role;
  std::lock_guard lock(handler_mutex_);
  return handler_store_.list_runs(filter);
}

std::vector<store::MetricPoint> RunManager::metrics(std::int64_t run_id) {
  std::lock_guard lock(handler_mutex_);
  return handler_store_.metrics(run_id);
}

std::vector<store::CheckpointInfo> RunManager::checkpoints(std::int64_t run_id) {
  std::lock_guard lock(handler_mutex_);
  handler_store_.get_run(run_id);  // NOT_FOUND for an unknown run
  return handler_store_.checkpoints(run_id);
}

std::optional<double> RunManager::eta_s(std::int64_t run_id) const {
  std::lock_guard lock(mutex_);
  if (!active_ || active_->run_id != run_id || active_->steps <= active_->start_steps)
    return std::nullopt;
  const double elapsed = std::chrono::duration<double>(Clock::now() - active_->started).count();
  const double rate = static_cast<double>(active_->steps - active_->start_steps) / elapsed;
  return static_cast<double>(std::max(0LL, active_->max_steps - active_->steps)) / rate;
}

RunManager::Load RunManager::load() const {
  std::lock_guard lock(mutex_);
  Load load;
  load.queued = queue_.size();
  if (!active_) return load;
  load.active = active_->run_id;
  load.active_env_steps = active_->steps;
  const double elapsed = std::chrono::duration<double>(Clock::now() - active_->started).count();
  if (active_->steps > active_->start_steps && elapsed > 0)
    load.active_steps_per_s = static_cast<double>(active_->steps - active_->start_steps) / elapsed;
  return load;
}

std::uint64_t RunManager::generation() const {
  std::lock_guard lock(mutex_);
  return generation_;
}

std::uint64_t RunManager::wait_for_change(std::uint64_t seen,
                                          std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mutex_);
  change_cv_.wait_for(lock, timeout, [&] { return generation_ != seen; });
  return generation_;
}

void RunManager::changed() {
  {
    std::lock_guard lock(mutex_);
    ++generation_;
  }
  change_cv_.notify_all();
}

void RunManager::work(std::stop_token shutdown) {
  store::RunStore store(options_.db_path);  // the worker's own connection
  for (;;) {
    std::int64_t run_id = 0;
    std::stop_token run_stop;
    {
      std::unique_lock lock(mutex_);
      if (!queue_cv_.wait(lock, shutdown, [&] { return !queue_.empty(); })) return;
      run_id = queue_.front();
      queue_.pop_front();
      active_.emplace();
      active_->run_id = run_id;
      run_stop = active_->stop.get_token();
    }
    train(store, run_id, run_stop, shutdown);
    {
      std::lock_guard lock(mutex_);
      active_.reset();
    }
    changed();
    if (shutdown.stop_requested()) return;
  }
}

void RunManager::train(store::RunStore& store, std::int64_t run_id, std::stop_token run_stop,
                       const std::stop_token& shutdown) {
  try {
    const store::RunRecord run = store.get_run(run_id);
    if (store::is_terminal(run.state)) return;
    const auto [spec, refs] = parse_config(run.spec.config_json);
    TrainingInputs inputs;
    if (refs.parent) inputs.init = store.load_checkpoint(*refs.parent).blob;
    for (std::size_t k = 0; k < refs.experts.size(); ++k)
      inputs.experts[k] = store.load_checkpoint(refs.experts[k]).blob;
    TrainingHooks hooks;
    hooks.threads = options_.threads;
    hooks.environments = options_.environments;
    // Resume: the last checkpoint's weights and the curve up to it.
    if (const auto latest = store.latest_checkpoint(run_id)) {
      inputs.init = store.load_checkpoint(latest->id).blob;
      for (const auto& m : store.metrics(run_id))
        if (m.env_steps <= latest->env_steps)
          hooks.control.resume_curve.push_back(to_curve_point(m));
    }
    const long long start_steps =
        hooks.control.resume_curve.empty() ? 0 : hooks.control.resume_curve.back().env_steps;
    {
      std::lock_guard lock(mutex_);
      active_->started = Clock::now();
      active_->start_steps = active_->steps = start_steps;
      active_->max_steps = spec.stop.max_steps;
    }
    store.set_state(run_id, store::RunState::kRunning);
    changed();
    // Shutdown stops the trainer too; the run then stays RUNNING, to resume next start.
    std::stop_source trainer_stop;
    std::stop_callback on_cancel(run_stop, [&] { trainer_stop.request_stop(); });
    std::stop_callback on_shutdown(shutdown, [&] { trainer_stop.request_stop(); });
    hooks.control.stop = trainer_stop.get_token();
    hooks.on_evaluation = [&](const rl::CurvePoint& p, const Blob& checkpoint) {
      store.record_evaluation(run_id, to_metric(p), checkpoint, false, std::nullopt);
      {
        std::lock_guard lock(mutex_);
        active_->steps = p.env_steps;
      }
      changed();
    };
    const TrainingOutcome outcome = train_role(spec, inputs, hooks, options_.code_commit);
    bool cancel_requested = false;
    {
      std::lock_guard lock(mutex_);
      cancel_requested = active_->cancel_requested;
    }
    if (outcome.result.cancelled) {
      if (cancel_requested) store.set_state(run_id, store::RunState::kCancelled);
      return;  // shut down: stays RUNNING
    }
    if (!outcome.result.curve.empty()) {  // the summary: reached and steps to target
      store.record_metric(run_id, to_metric(outcome.result.curve.back()), outcome.result.reached,
                          outcome.result.reached
                              ? std::optional<long long>(outcome.result.steps_to_target)
                              : std::nullopt);
    }
    store.set_state(run_id, store::RunState::kSucceeded);
  } catch (const std::exception& e) {
    try {
      store.set_state(run_id, store::RunState::kFailed, e.what());
    } catch (const std::exception&) {
      // The store itself failed: the run stays as it was and resumes at the next start.
    }
  }
}

}  // namespace pnp::training
