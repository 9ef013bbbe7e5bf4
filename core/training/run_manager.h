#pragma once
// Runs the training runs of one role against the store, one at a time, in the background:
// the core of a training service, with no gRPC in it.
//
// A run is validated completely (spec, and every checkpoint it references: present,
// intact, of the right role) before it is stored, so a refused request leaves nothing
// behind. While it trains, every evaluation is written with the checkpoint it evaluated
// in one transaction. A run still PENDING or RUNNING when the process stops (a crash, a
// SIGKILL, or a shutdown) is picked up again by the next RunManager of its role: it
// resumes from its last checkpoint with its learning curve intact.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

#include "store/run_store.h"
#include "training/role_training.h"
#include "training/training_spec.h"

namespace pnp::training {

// Checkpoints a run references, by id in the store.
struct CheckpointRefs {
  std::optional<std::int64_t> parent;  // fine-tune from it (same role)
  // Experts: those before the trained subtask, in subtask order (empty: scripted).
  // Choreographer: approach, manipulate, retract (empty: the promoted ones at creation).
  std::vector<std::int64_t> experts;
};

struct RunManagerOptions {
  std::string db_path;
  std::string role;                  // the one role this manager trains
  std::string code_commit;           // recorded with every run and checkpoint
  std::size_t threads = 0;           // trainer threads (0: all cores); results do not depend on it
  EnvironmentSource environments{};  // where rollouts run (empty: in this process)
};

class RunManager {
 public:
  // Opens the store and queues this role's interrupted runs, oldest first.
  explicit RunManager(const RunManagerOptions& options);
  // Stops the active run where it is, leaving it RUNNING so the next start resumes it.
  ~RunManager();
  RunManager(const RunManager&) = delete;
  RunManager& operator=(const RunManager&) = delete;

  const std::string& role() const { return options_.role; }

  // INVALID_ARGUMENT (spec, role, checkpoint roles), NOT_FOUND (checkpoint ids),
  // DATA_LOSS (corrupted checkpoint), FAILED_PRECONDITION (no promoted expert).
  store::RunRecord create(const TrainingSpec& spec, const CheckpointRefs& refs);
  // A pending run is cancelled at once; a running one stops at its next round. A finished
  // run is FAILED_PRECONDITION; another role's run is FAILED_PRECONDITION too (its own
  // service owns it).
  store::RunRecord cancel(std::int64_t run_id);

  // Reads, serialised on one connection (handlers call these from many threads).
  store::RunRecord get(std::int64_t run_id);
  std::vector<store::RunRecord> list(store::RunFilter filter);
  std::vector<store::MetricPoint> metrics(std::int64_t run_id);
  std::vector<store::CheckpointInfo> checkpoints(std::int64_t run_id);

  // Seconds to the run's step cap at its current rate (an upper bound: it stops sooner if
  // it reaches its target); empty unless it is training now and has a rate.
  std::optional<double> eta_s(std::int64_t run_id) const;

  // What the worker is doing now, for monitoring (Prometheus gauges in the service).
  struct Load {
    std::size_t queued = 0;              // runs waiting behind the active one
    std::optional<std::int64_t> active;  // the run training now
    long long active_env_steps = 0;      // its training env steps so far
    double active_steps_per_s = 0;       // since it (re)started; 0 before its first report
  };
  Load load() const;

  // A counter bumped at every change to any run; wait_for_change returns when it differs
  // from `seen` or after `timeout`, with its current value.
  std::uint64_t generation() const;
  std::uint64_t wait_for_change(std::uint64_t seen, std::chrono::milliseconds timeout) const;

 private:
  struct Active {
    std::int64_t run_id = 0;
    std::stop_source stop;
    std::chrono::steady_clock::time_point started;
    long long start_steps = 0, steps = 0, max_steps = 0;
    bool cancel_requested = false;
  };

  void work(std::stop_token shutdown);
  void train(store::RunStore& store, std::int64_t run_id, std::stop_token run_stop,
             const std::stop_token& shutdown);
  void changed();

  RunManagerOptions options_;
  std::mutex handler_mutex_;
  store::RunStore handler_store_;  // for request handlers; guarded by handler_mutex_

  mutable std::mutex mutex_;
  std::condition_variable_any queue_cv_;
  mutable std::condition_variable change_cv_;
  std::deque<std::int64_t> queue_;
  std::optional<Active> active_;
  std::uint64_t generation_ = 0;

  std::jthread worker_;  // last: stopped and joined before the members above go
};

}  // namespace pnp::training
