#pragma once
// Runs the training runs of one role against the store, one at a time, in the background:
// the core of a training service, with no gRPC in it.
//
// A run is validated completely (spec, and every checkpoint it references: present,
// intact, of the right role) before it is stored, so a refused request leaves nothing
// behind. The worker claims runs from the store (store::Store::claim_next) and holds
// each with a lease that a heartbeat renews, so several managers of one role on one store
// (several servers, or a restarted one beside a hung one) never train the same run: a run
// whose owner stops renewing (killed, hung) is taken over by another manager once its
// lease expires, and resumes from its last checkpoint with its learning curve intact.
// While it trains, every evaluation is written with the checkpoint it evaluated in one
// transaction, by its owner only. A busy database pauses a run (retried with backoff,
// then the run goes back to the queue) instead of failing it; FAILED is for errors of the
// training itself. A trainer stopped between evaluations (a clean shutdown, a cancel)
// leaves its weights as one more checkpoint, and the run resumes from them.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

#include "store/retry.h"
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
  // Experts: those after the trained subtask in evaluation, in subtask order (empty:
  // scripted; backward chaining, docs/LEARNING.md).
  std::vector<std::int64_t> successors;
};

struct RunManagerOptions {
  std::string db_path;  // the SQLite store, opened in this process, unless open_store is set

  std::string role;                  // the one role this manager trains
  std::string code_commit;           // recorded with every run and checkpoint
  std::size_t threads = 0;           // trainer threads (0: all cores); results do not depend on it
  EnvironmentSource environments{};  // where rollouts run (empty: in this process)
  // This manager's name in run leases (empty: host:pid:start time, unique per process).
  std::string owner{};
  // A run whose owner has not renewed its lease for this long may be taken over; the
  // heartbeat renews it every lease / 4, and an idle worker looks for runs as often.
  std::chrono::milliseconds lease = std::chrono::seconds(10);
  store::RetryPolicy retry{};  // store writes while the database is busy
  // Checkpoints kept per run besides its best, promoted and referenced ones (pruned after
  // every evaluation); empty keeps all.
  std::optional<store::RetentionPolicy> retention = store::RetentionPolicy{};
  // Where the worker reports what it could not do (a busy store, a run taken over); the
  // service passes its logger. Empty: standard error.
  std::function<void(const std::string&)> log{};
  // Opens one handle on the store (the manager keeps one per thread); empty: a RunStore on
  // db_path. A server whose store is pnp-store-server passes a RemoteStore opener.
  store::StoreOpener open_store{};
};

class RunManager {
 public:
  // Opens the store and starts the worker, which takes this role's pending and interrupted
  // runs, oldest first.
  explicit RunManager(const RunManagerOptions& options);
  // Stops the active run where it is and releases it (still RUNNING): another manager of
  // the role, or the next start, resumes it.
  ~RunManager();
  RunManager(const RunManager&) = delete;
  RunManager& operator=(const RunManager&) = delete;

  const std::string& role() const { return options_.role; }
  const std::string& owner() const { return options_.owner; }

  // INVALID_ARGUMENT (spec, role, checkpoint roles), NOT_FOUND (checkpoint ids),
  // DATA_LOSS (corrupted checkpoint), FAILED_PRECONDITION (no promoted expert).
  // `request_id`: the idempotency key (store::Store::create_run), scoped by the caller.
  store::RunRecord create(const TrainingSpec& spec, const CheckpointRefs& refs,
                          const std::string& request_id = "");
  // A pending run is cancelled at once; a running one stops at its next round (here, or on
  // the manager that holds it, at its next heartbeat). A finished run is
  // FAILED_PRECONDITION; another role's run is FAILED_PRECONDITION too (its own service
  // owns it).
  store::RunRecord cancel(std::int64_t run_id);

  // Reads, serialised on one connection (handlers call these from many threads).
  store::RunRecord get(std::int64_t run_id);
  std::vector<store::RunRecord> list(store::RunFilter filter);
  std::vector<store::MetricPoint> metrics(std::int64_t run_id);
  std::vector<store::MetricPoint> metrics_after(std::int64_t run_id, long long after_env_steps);
  std::vector<store::CheckpointInfo> checkpoints(std::int64_t run_id);

  // Seconds to the run's step cap at its current rate (an upper bound: it stops sooner if
  // it reaches its target); empty unless it is training now and has a rate.
  std::optional<double> eta_s(std::int64_t run_id) const;

  // What the worker is doing now, for monitoring (Prometheus gauges in the service).
  struct Load {
    std::size_t queued = 0;              // runs of the role waiting for a worker
    std::optional<std::int64_t> active;  // the run training now
    long long active_env_steps = 0;      // its training env steps so far
    double active_steps_per_s = 0;       // since it (re)started; 0 before its first report
    long long store_write_errors = 0;    // writes failed for a reason other than a busy lock
    bool store_faulty = false;           // the last write failed so (store_fault())
  };
  Load load();

  // Why the store cannot be used, if the last write this manager tried failed for a reason
  // other than a busy lock (a full disk, a read-only file, an I/O error); empty once a
  // later write succeeds. The service reports NOT_SERVING meanwhile.
  std::optional<std::string> store_fault() const;

  // A counter bumped at every change to any run; wait_for_change returns when it differs
  // from `seen` or after `timeout`, with its current value.
  std::uint64_t generation() const;
  std::uint64_t wait_for_change(std::uint64_t seen, std::chrono::milliseconds timeout) const;

 private:
  struct Active {
    // Declared, so that std::optional<Active> is constructible inside this class too
    // (clang evaluates that before the member initialisers below are parsed).
    Active() noexcept {}  // NOLINT(modernize-use-equals-default)
    std::int64_t run_id = 0;
    std::stop_source stop;
    std::chrono::steady_clock::time_point started;
    long long start_steps = 0, steps = 0, max_steps = 0;
    bool cancel_requested = false;
    bool lost = false;  // cancelled elsewhere or taken over: write nothing more
  };
  // How a claimed run's turn ended.
  enum class Turn { kFinished, kReleased, kRequeued };

  void work(std::stop_token shutdown);
  void heartbeat(std::stop_token shutdown);
  Turn train(store::Store& store, const store::RunRecord& run, std::stop_token run_stop,
             const std::stop_token& shutdown);
  // Adds the trainer's part of the run's wall time to the run's sums (reported, not thrown,
  // if the store refuses it).
  void record_wall_time(store::Store& store, std::int64_t run_id, const WallBreakdown& part);
  // Keeps the weights of a trainer stopped between evaluations (shutdown or cancel).
  void save_final_weights(store::Store& store, std::int64_t run_id, const TrainingOutcome& outcome,
                          long long start_steps);
  Turn finish(store::Store& store, std::int64_t run_id, store::RunState state,
              const std::string& error, const std::stop_token& shutdown);
  void sleep_until_woken(std::chrono::milliseconds timeout, const std::stop_token& shutdown);
  void report(const std::string& message) const;
  // A store write succeeded (`failure` null) or failed: store_fault() follows the last one.
  void note_store_write(const std::exception* failure);
  void changed();

  RunManagerOptions options_;
  std::mutex handler_mutex_;
  std::unique_ptr<store::Store> handler_store_;  // for request handlers; guarded by handler_mutex_

  mutable std::mutex mutex_;
  std::condition_variable_any wake_cv_;
  mutable std::condition_variable change_cv_;
  bool woken_ = false;  // a run was created or cancelled since the worker last looked
  std::optional<Active> active_;
  std::uint64_t generation_ = 0;
  std::optional<std::string> store_fault_;  // guarded by mutex_
  long long store_write_errors_ = 0;        // guarded by mutex_

  // Last: stopped and joined before the members above go.
  std::jthread worker_;
  std::jthread heartbeat_;
};

}  // namespace pnp::training
