#pragma once
// What the store keeps: training runs, their learning curves, their checkpoints, and
// which checkpoint serves each role. Plain values; the store validates them.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/roles.h"
#include "common/wall_breakdown.h"

namespace pnp::store {

enum class RunState { kPending, kRunning, kSucceeded, kFailed, kCancelled };
std::string_view run_state_name(RunState state);
RunState parse_run_state(std::string_view name, std::string_view field = "state");
bool is_terminal(RunState state);
// What every client shows for a run (pnpctl, the dashboard, the Python package): a run that
// finished normally "reached" its target or is "not-reached" (stopped at its step cap);
// otherwise its state (pending, running, failed, cancelled).
std::string_view run_outcome(RunState state, bool reached);

// The roles a run or a checkpoint can have (common/roles.h); anything else is refused.
using pnp::is_known_role;
using pnp::kRoles;

// The longest idempotency key of a run's creation (Store::create_run's request_id), as a
// server scopes it ("<principal>/<client's key>", a client's key at most 128 bytes).
inline constexpr std::size_t kMaxRequestIdBytes = 512;

using Millis = std::int64_t;  // Unix time in milliseconds

// The longest phase of one trainer's part of a run the store accepts (Store::add_wall_time):
// about 116 days, far past any run; more is a broken clock or a forged request.
inline constexpr double kMaxWallPartSeconds = 1e7;

struct RunSpec {
  std::string role;       // approach, manipulate, retract, hlc or e2e
  std::string algorithm;  // ddpg_her, bc, bc_offline, a3c
  std::string robot, object;
  std::uint64_t seed = 0;
  std::string config_json = "{}";  // every hyperparameter, as the trainer received it
  std::string code_commit;
  std::optional<std::int64_t> parent_checkpoint_id;  // fine-tuning starts from it
  // The GEMM path of the process that created the run (nn/gemm_path.h): runs on different
  // paths give different, equally valid curves. Empty for runs from before it was kept.
  std::string gemm_path{};
};

struct RunRecord {
  std::int64_t id = 0;
  RunSpec spec;
  RunState state = RunState::kPending;
  Millis created_ms = 0, updated_ms = 0;
  std::optional<Millis> finished_ms;
  std::string error;  // why it failed, empty otherwise
  long long env_steps = 0;
  double last_success = 0;
  std::optional<double> last_score;  // the stop rule's score at the last evaluation
  bool reached = false;
  std::optional<long long> steps_to_target;
  // The training server that holds the run (empty: none) and until when; another server
  // of the role may take the run over once the lease has expired.
  std::string owner;
  std::optional<Millis> lease_expires_ms;
  // Where the run's wall time went: the sum of the parts its trainers recorded as they
  // stopped (Store::add_wall_time), all zero until the first part ends.
  WallBreakdown wall{};
};

struct MetricPoint {
  long long env_steps = 0;
  long long episodes = 0;
  double wall_s = 0;
  double task_success = 0;
  double subtask_success = 0;
  double sampled_success = 0;
  double critic_loss = 0;
  double actor_loss = 0;
  long long updates = 0;
  // What the run's stop rule compared with its target (experts: the lower of task and
  // subtask success; the choreographer: task success). Empty for evaluations stored
  // before the store kept it.
  std::optional<double> stop_score{};
};

// Where a trainer stood when it saved weights between evaluations (stopped by a shutdown
// or a cancel): what it resumes its counters from. The step count is the checkpoint's.
struct TrainerCounters {
  long long episodes = 0;
  long long updates = 0;
  double wall_s = 0;
  double eval_wall_s = 0;
};

struct CheckpointInfo {
  std::int64_t id = 0;
  std::int64_t run_id = 0;
  std::string role;
  long long env_steps = 0;
  double eval_success = 0;  // of the evaluation at env_steps; 0 if never evaluated
  std::string checksum;     // FNV-1a 64 of the blob, hex
  std::int64_t size_bytes = 0;
  Millis created_ms = 0;
  // Set for weights saved between evaluations: never evaluated themselves.
  std::optional<TrainerCounters> unevaluated{};
};

struct Checkpoint {
  CheckpointInfo info;
  std::vector<std::uint8_t> blob;  // verified against info.checksum
};

struct Promotion {
  std::string role;
  std::int64_t checkpoint_id = 0;
  Millis promoted_ms = 0;
  std::string promoted_by{};  // the authorized principal; empty without an auth policy
};

// One call of an operator or robot RPC (security/rpc_access.h), as the audit trail keeps it.
struct AuditRecord {
  std::int64_t id = 0;
  Millis ts_ms = 0;
  std::string service;    // inference, train-approach, robot-sim...
  std::string principal;  // empty: no auth policy configured
  std::string peer;       // the caller's address as gRPC saw it
  std::string rpc;        // full method path
  std::string request;    // the first request message as JSON, cut at 2 KB
  std::string code;       // the final status: OK, PERMISSION_DENIED...
  // Who wrote the record into the store: empty for the server that answered the call (it
  // appended it itself); for a batch another server forwarded (AppendAudit), that server as
  // the store authenticated it, never as the batch says.
  std::string recorded_by{};
  Millis received_ms = 0;  // when the store received it; 0: at ts_ms (written by itself)
};

}  // namespace pnp::store
