#include "training/run_manager.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <functional>
#include <iostream>
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
  nlohmann::json checkpoints = {{"experts", refs.experts}, {"successors", refs.successors}};
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
  // Runs stored before successors existed evaluated with scripted ones.
  refs.successors = checkpoints.value("successors", std::vector<std::int64_t>{});
  return {spec_from_json(j.at("spec")), refs};
}

// A stored checkpoint, checked to be of `role`.
store::Checkpoint load_of_role(store::Store& store, std::int64_t id, const std::string& role,
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

std::string default_owner() {
  std::array<char, 256> host{};
  if (::gethostname(host.data(), host.size() - 1) != 0) host[0] = '\0';
  return std::string(host.data()) + ":" + std::to_string(::getpid()) + ":" +
         std::to_string(store::now_ms());
}

RunManagerOptions completed(RunManagerOptions options) {
  if (options.owner.empty()) options.owner = default_owner();
  if (options.lease < std::chrono::milliseconds(100))
    throw_invalid_argument("lease", "at least 100 ms",
                           std::to_string(options.lease.count()) + " ms");
  if (!options.log) options.log = [](const std::string& line) { std::cerr << line << std::endl; };
  if (!options.open_store) {
    options.open_store = [path = options.db_path]() -> std::unique_ptr<store::Store> {
      return std::make_unique<store::RunStore>(path);
    };
  }
  return options;
}

}  // namespace

RunManager::RunManager(const RunManagerOptions& options)
    : options_(completed(options)), handler_store_(options_.open_store()) {
  if (!store::is_known_role(options_.role))
    throw_invalid_argument("role", "one of approach, manipulate, retract, hlc, e2e",
                           "\"" + options_.role + "\"");
  options_.retry.jitter_seed = std::hash<std::string>{}(options_.owner);
  worker_ = std::jthread([this](std::stop_token shutdown) { work(shutdown); });
  heartbeat_ = std::jthread([this](std::stop_token shutdown) { heartbeat(shutdown); });
}

RunManager::~RunManager() {
  heartbeat_.request_stop();
  worker_.request_stop();
}  // then the threads are joined (declared last), before the members they use go

store::RunRecord RunManager::create(const TrainingSpec& spec, const CheckpointRefs& given,
                                    const std::string& request_id) {
  if (spec.role != options_.role) {
    throw_invalid_argument("role", "\"" + options_.role + "\" (this service's role)",
                           "\"" + spec.role + "\"");
  }
  spec.validate();
  CheckpointRefs refs = given;
  std::lock_guard lock(handler_mutex_);
  if (refs.parent)
    check_parent_shape(
        spec, load_of_role(*handler_store_, *refs.parent, spec.role, "parent_checkpoint_id"));
  if (spec.role == "hlc") {
    if (refs.experts.empty()) {
      for (std::size_t k = 0; k < sim::kNumSubtasks; ++k) {
        const auto promoted = handler_store_->promoted(expert_role(k));
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
    load_of_role(*handler_store_, refs.experts[k], expert_role(k),
                 (spec.role == "hlc" ? "expert_checkpoint_ids[" : "prefix_checkpoint_ids[") +
                     std::to_string(k) + "]");
  }
  if (!refs.successors.empty()) {
    const std::size_t own =
        spec.is_expert() ? static_cast<std::size_t>(sim::parse_subtask(spec.role)) : 0;
    const std::size_t after = spec.is_expert() ? sim::kNumSubtasks - own - 1 : 0;
    if (refs.successors.size() != after) {
      throw_invalid_argument(
          "successor_checkpoint_ids",
          spec.is_expert() ? std::to_string(after) + " ids (the experts after " + spec.role + ")"
                           : "none (only subtask experts take them)",
          std::to_string(refs.successors.size()) + " ids");
    }
    for (std::size_t k = 0; k < after; ++k) {
      load_of_role(*handler_store_, refs.successors[k], expert_role(own + 1 + k),
                   "successor_checkpoint_ids[" + std::to_string(k) + "]");
    }
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
  store::RunRecord run;
  try {
    run = handler_store_->create_run(record, request_id);
  } catch (const std::exception& e) {
    note_store_write(&e);
    throw;
  }
  note_store_write(nullptr);
  {
    std::lock_guard wake_lock(mutex_);
    woken_ = true;
  }
  wake_cv_.notify_all();
  changed();
  return run;
}

store::RunRecord RunManager::cancel(std::int64_t run_id) {
  std::lock_guard lock(handler_mutex_);
  const store::RunRecord run = handler_store_->get_run(run_id);
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
    std::lock_guard lock_active(mutex_);
    if (active_ && active_->run_id == run_id) {
      active_->cancel_requested = true;
      active_->stop.request_stop();
      return run;  // the worker records CANCELLED when the trainer returns
    }
  }
  // Pending, or held by another manager of the role: that one stops it at its next
  // heartbeat, when renewing the lease finds the run cancelled.
  const store::RunRecord cancelled = handler_store_->set_state(run_id, store::RunState::kCancelled);
  changed();
  return cancelled;
}

store::RunRecord RunManager::get(std::int64_t run_id) {
  std::lock_guard lock(handler_mutex_);
  return handler_store_->get_run(run_id);
}

std::vector<store::RunRecord> RunManager::list(store::RunFilter filter) {
  filter.role = options_.role;
  std::lock_guard lock(handler_mutex_);
  return handler_store_->list_runs(filter);
}

std::vector<store::MetricPoint> RunManager::metrics(std::int64_t run_id) {
  std::lock_guard lock(handler_mutex_);
  return handler_store_->metrics(run_id);
}

std::vector<store::MetricPoint> RunManager::metrics_after(std::int64_t run_id,
                                                          long long after_env_steps) {
  std::lock_guard lock(handler_mutex_);
  return handler_store_->metrics_after(run_id, after_env_steps);
}

std::vector<store::CheckpointInfo> RunManager::checkpoints(std::int64_t run_id) {
  std::lock_guard lock(handler_mutex_);
  handler_store_->get_run(run_id);  // NOT_FOUND for an unknown run
  return handler_store_->checkpoints(run_id);
}

std::optional<double> RunManager::eta_s(std::int64_t run_id) const {
  std::lock_guard lock(mutex_);
  if (!active_ || active_->run_id != run_id || active_->steps <= active_->start_steps)
    return std::nullopt;
  const double elapsed = std::chrono::duration<double>(Clock::now() - active_->started).count();
  const double rate = static_cast<double>(active_->steps - active_->start_steps) / elapsed;
  return static_cast<double>(std::max(0LL, active_->max_steps - active_->steps)) / rate;
}

RunManager::Load RunManager::load() {
  std::int64_t claimable = 0;
  {
    std::lock_guard lock(handler_mutex_);
    claimable = handler_store_->count_claimable(options_.role, options_.owner);
  }
  std::lock_guard lock(mutex_);
  Load load;
  load.store_write_errors = store_write_errors_;
  load.store_faulty = store_fault_.has_value();
  // The store's queue for this role, less the run this manager trains (which it owns).
  load.queued = static_cast<std::size_t>(std::max<std::int64_t>(0, claimable - (active_ ? 1 : 0)));
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

void RunManager::report(const std::string& message) const {
  options_.log("training worker (" + options_.role + ", " + options_.owner + "): " + message);
}

void RunManager::note_store_write(const std::exception* failure) {
  const auto* store_error = dynamic_cast<const store::StoreError*>(failure);
  if (failure && (!store_error || dynamic_cast<const store::BusyError*>(failure))) return;
  std::lock_guard lock(mutex_);
  if (failure) {
    store_fault_ = failure->what();
    ++store_write_errors_;
  } else {
    store_fault_.reset();
  }
}

std::optional<std::string> RunManager::store_fault() const {
  std::lock_guard lock(mutex_);
  return store_fault_;
}

void RunManager::sleep_until_woken(std::chrono::milliseconds timeout,
                                   const std::stop_token& shutdown) {
  std::unique_lock lock(mutex_);
  wake_cv_.wait_for(lock, shutdown, timeout, [&] { return woken_; });
  woken_ = false;
}

void RunManager::work(std::stop_token shutdown) {
  // The worker's own connection, opened here and reopened after a failure: nothing that
  // goes wrong in this thread may end the process (an escaping exception would call
  // std::terminate with no word of why).
  std::unique_ptr<store::Store> store;
  int failures = 0;
  const auto poll = options_.lease / 4;
  while (!shutdown.stop_requested()) {
    std::optional<store::RunRecord> claimed;
    try {
      if (!store) store = options_.open_store();
      claimed = store::with_retry(
          options_.retry,
          [&] { return store->claim_next(options_.role, options_.owner, options_.lease); },
          shutdown);
      failures = 0;
      if (claimed) note_store_write(nullptr);  // the claim was a write
    } catch (const std::exception& e) {
      if (shutdown.stop_requested()) return;
      note_store_write(&e);
      report(std::string("looking for runs: ") + e.what() + "; trying again");
      if (!dynamic_cast<const store::BusyError*>(&e)) store.reset();
      store::sleep_unless_stopped(store::retry_backoff(options_.retry, failures++), shutdown);
      continue;
    }
    if (!claimed) {
      sleep_until_woken(poll, shutdown);
      continue;
    }
    std::stop_token run_stop;
    {
      std::lock_guard lock(mutex_);
      active_.emplace();
      active_->run_id = claimed->id;
      run_stop = active_->stop.get_token();
    }
    changed();
    const Turn turn = train(*store, *claimed, run_stop, shutdown);
    {
      std::lock_guard lock(mutex_);
      active_.reset();
    }
    if (turn == Turn::kReleased) {
      try {  // best effort: if this fails, the lease expires and another manager resumes it
        store->release(claimed->id, options_.owner);
      } catch (const std::exception& e) {
        report("run " + std::to_string(claimed->id) + ": releasing it: " + e.what());
      }
    }
    changed();
    if (turn == Turn::kRequeued) sleep_until_woken(poll, shutdown);
  }
}

void RunManager::heartbeat(std::stop_token shutdown) {
  std::unique_ptr<store::Store> store;
  while (store::sleep_unless_stopped(options_.lease / 4, shutdown)) {
    std::int64_t run_id = 0;
    {
      std::lock_guard lock(mutex_);
      if (!active_ || active_->lost) continue;
      run_id = active_->run_id;
    }
    try {
      if (!store) store = options_.open_store();
      if (store->renew_lease(run_id, options_.owner, options_.lease)) {
        note_store_write(nullptr);
        continue;
      }
      bool stopped = false;
      {
        std::lock_guard lock(mutex_);
        if (active_ && active_->run_id == run_id && !active_->cancel_requested) {
          active_->lost = true;
          active_->stop.request_stop();
          stopped = true;
        }
      }
      if (stopped) {
        report("run " + std::to_string(run_id) +
               " is no longer held by this server (cancelled, or taken over after its lease "
               "expired): stopping its trainer");
      }
    } catch (const std::exception& e) {
      // Tried again at the next beat. Should the lease lapse meanwhile and another manager
      // take the run, this one's next write is refused (ABORTED) and it stops then.
      report("run " + std::to_string(run_id) + ": renewing its lease: " + e.what());
      note_store_write(&e);
      if (!dynamic_cast<const store::BusyError*>(&e)) store.reset();
    }
  }
}

RunManager::Turn RunManager::finish(store::Store& store, std::int64_t run_id, store::RunState state,
                                    const std::string& error, const std::stop_token& shutdown) {
  try {
    store::with_retry(
        options_.retry, [&] { store.set_state(run_id, state, error, options_.owner); }, shutdown);
    return Turn::kFinished;
  } catch (const store::BusyError& e) {
    // Never recorded as failed for a busy store, never stranded: the run stays this
    // manager's and RUNNING, and is taken up again (resumed from its last checkpoint).
    report("run " + std::to_string(run_id) + ": recording it " +
           std::string(store::run_state_name(state)) + ": " + e.what() + "; back to the queue");
    return Turn::kRequeued;
  } catch (const Error& e) {
    report("run " + std::to_string(run_id) + ": recording it " +
           std::string(store::run_state_name(state)) + ": " + e.what());
    return Turn::kFinished;  // cancelled or taken over meanwhile: it is not ours to record
  }
}

void RunManager::record_wall_time(store::Store& store, std::int64_t run_id,
                                  const WallBreakdown& part) {
  try {
    // One attempt: a lost part costs the run's breakdown one process's share, never the
    // run, and a shutdown does not wait out the retry budget for it.
    store.add_wall_time(run_id, part, options_.owner);
  } catch (const std::exception& e) {
    report("run " + std::to_string(run_id) + ": its wall time (" + std::to_string(part.total_s) +
           " s) was not recorded: " + e.what());
  }
}

void RunManager::save_final_weights(store::Store& store, std::int64_t run_id,
                                    const TrainingOutcome& outcome, long long start_steps) {
  const rl::TrainingResult& result = outcome.result;
  const long long evaluated = result.curve.empty() ? 0 : result.curve.back().env_steps;
  // Nothing trained since the last checkpoint (the trainer stopped at an evaluation, or
  // before its first round): that checkpoint already holds these weights.
  if (result.train_env_steps <= std::max(evaluated, start_steps)) return;
  try {
    // One attempt plus the connection's busy timeout: a shutdown does not wait out the
    // retry budget, and losing these weights costs at most one evaluation interval.
    const auto saved = store.save_unevaluated(
        run_id, result.train_env_steps,
        {result.train_episodes, result.updates, result.wall_s, result.eval_wall_s},
        outcome.checkpoint, options_.owner);
    report("run " + std::to_string(run_id) + ": stopped at " +
           std::to_string(result.train_env_steps) + " steps; its weights are checkpoint " +
           std::to_string(saved.id));
  } catch (const std::exception& e) {
    report("run " + std::to_string(run_id) + ": its final weights (" +
           std::to_string(result.train_env_steps) + " steps) were not saved: " + e.what() +
           "; it resumes from its last evaluation");
    return;
  }
  if (!options_.retention) return;
  try {
    store.prune_checkpoints(run_id, *options_.retention);
  } catch (const std::exception& e) {  // the next evaluation, or pnpctl gc, prunes it
    report("run " + std::to_string(run_id) + ": retention deferred: " + e.what());
  }
}

RunManager::Turn RunManager::train(store::Store& store, const store::RunRecord& run,
                                   std::stop_token run_stop, const std::stop_token& shutdown) {
  const std::int64_t run_id = run.id;
  const auto lost = [&] {
    std::lock_guard lock(mutex_);
    return active_->lost;
  };
  try {
    const auto [spec, refs] = parse_config(run.spec.config_json);
    TrainingInputs inputs;
    if (refs.parent) inputs.init = store.load_checkpoint(*refs.parent).blob;
    for (std::size_t k = 0; k < refs.experts.size(); ++k)
      inputs.experts[k] = store.load_checkpoint(refs.experts[k]).blob;
    const std::size_t first_after =
        sim::kNumSubtasks - refs.successors.size();  // successors end at retract
    for (std::size_t k = 0; k < refs.successors.size(); ++k)
      inputs.experts[first_after + k] = store.load_checkpoint(refs.successors[k]).blob;
    TrainingHooks hooks;
    hooks.threads = options_.threads;
    hooks.environments = options_.environments;
    // Resume: the intact weights with the most training steps and the curve up to them. A
    // damaged checkpoint (DATA_LOSS) is passed over for the one before it.
    const auto saved = store.checkpoints(run_id);
    for (auto c = saved.rbegin(); c != saved.rend(); ++c) {
      try {
        inputs.init = store.load_checkpoint(c->id).blob;
      } catch (const Error& e) {
        if (e.code() != ErrorCode::kDataLoss) throw;
        report("run " + std::to_string(run_id) + ": " + e.what() +
               "; resuming from an earlier one");
        continue;
      }
      for (const auto& m : store.metrics(run_id))
        if (m.env_steps <= c->env_steps) hooks.control.resume_curve.push_back(to_curve_point(m));
      if (c->unevaluated) {  // saved when the trainer last stopped, between evaluations
        const store::TrainerCounters& at = *c->unevaluated;
        hooks.control.resume_counters =
            rl::TrainingCounters{c->env_steps, at.episodes, at.updates, at.wall_s, at.eval_wall_s};
      }
      break;
    }
    const long long start_steps =
        hooks.control.resume_counters        ? hooks.control.resume_counters->env_steps
        : hooks.control.resume_curve.empty() ? 0
                                             : hooks.control.resume_curve.back().env_steps;
    {
      std::lock_guard lock(mutex_);
      active_->started = Clock::now();
      active_->start_steps = active_->steps = start_steps;
      active_->max_steps = spec.stop.max_steps;
    }
    changed();
    // Shutdown stops the trainer too; the run then stays RUNNING, released for another
    // manager (or the next start) to resume.
    std::stop_source trainer_stop;
    std::stop_callback on_cancel(run_stop, [&] { trainer_stop.request_stop(); });
    std::stop_callback on_shutdown(shutdown, [&] { trainer_stop.request_stop(); });
    hooks.control.stop = trainer_stop.get_token();
    hooks.control.on_steps = [&](long long env_steps) {
      std::lock_guard lock(mutex_);
      active_->steps = env_steps;
    };
    hooks.on_evaluation = [&](const rl::CurvePoint& p, const Blob& checkpoint) {
      store::with_retry(
          options_.retry,
          [&] {
            store.record_evaluation(run_id, to_metric(p), checkpoint, false, std::nullopt,
                                    options_.owner);
          },
          shutdown);
      note_store_write(nullptr);
      if (options_.retention) {
        try {
          store.prune_checkpoints(run_id, *options_.retention);
        } catch (const store::BusyError&) {  // the next evaluation prunes what is left
        }
      }
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
    if (lost()) return Turn::kFinished;  // cancelled elsewhere or taken over
    record_wall_time(store, run_id, outcome.result.breakdown);
    if (outcome.result.cancelled) {
      save_final_weights(store, run_id, outcome, start_steps);
      if (cancel_requested) return finish(store, run_id, store::RunState::kCancelled, "", shutdown);
      return Turn::kReleased;  // shut down
    }
    if (!outcome.result.curve.empty()) {  // the summary: reached and steps to target
      store::with_retry(
          options_.retry,
          [&] {
            store.record_metric(
                run_id, to_metric(outcome.result.curve.back()), outcome.result.reached,
                outcome.result.reached ? std::optional<long long>(outcome.result.steps_to_target)
                                       : std::nullopt,
                options_.owner);
          },
          shutdown);
    }
    return finish(store, run_id, store::RunState::kSucceeded, "", shutdown);
  } catch (const store::BusyError& e) {
    if (shutdown.stop_requested()) return Turn::kReleased;
    report("run " + std::to_string(run_id) + ": the store stayed busy (" + e.what() +
           "); the run pauses and goes back to the queue");
    return Turn::kRequeued;
  } catch (const std::exception& e) {
    const auto* error = dynamic_cast<const Error*>(&e);
    if (lost() || (error && error->code() == ErrorCode::kAborted)) {
      report("run " + std::to_string(run_id) +
             ": stopped, no longer held by this server: " + e.what());
      return Turn::kFinished;
    }
    note_store_write(&e);  // a store that failed the run makes the service unhealthy
    return finish(store, run_id, store::RunState::kFailed, e.what(), shutdown);
  }
}

}  // namespace pnp::training
