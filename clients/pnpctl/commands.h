#pragma once
// pnpctl's commands: each a function over the service endpoints and its own arguments.
// They print tables on stdout and progress on stderr, and throw pnp::Error (one clear
// line, non-zero exit) when a call fails.

#include <cstdint>
#include <string>
#include <vector>

#include "clients/pnpctl/endpoints.h"
#include "pnp/train/v1/train_service.pb.h"
#include "services/store/store_flags.h"
#include "training/training_spec.h"

namespace pnp::pnpctl {

// A training request as typed on the command line; zero or empty means "the service's
// default" for every hyperparameter.
struct TrainArgs {
  std::string role = "approach";
  std::string algorithm;  // empty: ddpg_her for experts and e2e, a3c for hlc
  std::string robot = "fetch", object = "block";
  std::string world{sim::world_profile_name(sim::kDefaultWorldProfile)};  // docs/SIMULATION.md
  std::string actuation = "default";             // mocap, arm or the robot's own (sim/actuation.h)
  std::string preset{training::kDefaultPreset};  // training/preset.h; unset fields take its values
  std::uint64_t seed = 0;
  long long max_steps = 0;
  double target_success = 0;
  long long eval_interval = 0;
  int eval_episodes = 0;
  double updates_per_transition = 0;
  std::vector<int> hidden;
  int workers = 0;
  std::int64_t parent = 0;
  std::vector<std::int64_t> prefix, experts, successors;
  bool detach = false;  // return once created
  bool quiet = false;   // no progress bar
};
train::v1::CreateTrainingRunRequest make_request(const TrainArgs& args);

int train_command(const Endpoints& endpoints, const TrainArgs& args);
// Cancels a pending or running run, found through `via`'s service (any role: they share
// the store) and cancelled by its own role's service.
int cancel_command(const Endpoints& endpoints, std::int64_t run_id, const std::string& via);
// role empty: every role's service that answers.
int runs_command(const Endpoints& endpoints, const std::string& role, const std::string& state,
                 int limit, bool csv);
int metrics_command(const Endpoints& endpoints, const std::string& role, std::int64_t run_id,
                    bool csv);
// A run's checkpoints, oldest first; the last is the one a pipeline promotes.
int checkpoints_command(const Endpoints& endpoints, const std::string& role, std::int64_t run_id,
                        bool csv);
// Learning curves as SVG: each run's stop score (metric "score") or task success
// ("success") against its training steps, labelled by role, algorithm and seed.
int plot_command(const Endpoints& endpoints, const std::string& role,
                 const std::vector<std::int64_t>& run_ids, const std::string& metric,
                 const std::string& out);
// Deletes the checkpoints retention does not keep (store::RetentionPolicy) from the store
// file at `db_path`, and gives the freed pages back to the filesystem.
int gc_command(const std::string& db_path, int keep_last, bool json);

// A consistent copy of the store (store/backup.h) into the new file `destination`, from
// the store file `db` or through the store server `store`.
struct BackupArgs {
  std::string destination;
  std::string db;
  services::RemoteStoreFlags store;
  bool json = false;
};
int backup_command(const BackupArgs& args);

// The audit trail of the store file at `db`, or of the store server at `store` (which
// wins): operator and robot calls, allowed or refused, oldest first (the newest `limit`
// since `since`: parse_since's forms).
struct AuditArgs {
  std::string db;
  services::RemoteStoreFlags store;
  std::string since;  // empty: from the start
  int limit = 1000;
  bool json = false;  // one JSON object per line
  bool wide = false;  // the whole request in the table
};
int audit_command(const AuditArgs& args);
// Several ids are promoted together, in one transaction (at most one per role).
int promote_command(const Endpoints& endpoints, const std::vector<std::int64_t>& checkpoint_ids);
// Promotes the latest checkpoint (the final model of a finished run) of each run, asking
// the training service of `via` (every one shares the store).
int promote_runs_command(const Endpoints& endpoints, const std::vector<std::int64_t>& run_ids,
                         const std::string& via);

struct PredictArgs {
  std::vector<double> observation, goal;  // given directly, or
  std::uint64_t seed = 0;                 // the first observation of the sim's episode
  std::string robot = "fetch", object = "block";
  std::string world{sim::world_profile_name(sim::kDefaultWorldProfile)};
  std::string actuation = "default";
};
int predict_command(const Endpoints& endpoints, const PredictArgs& args);
// Checks the named services (sim, approach, manipulate, retract, hlc, e2e, inference);
// 0 when every one is SERVING but those in `optional`, which are shown and never fail it.
int health_command(const Endpoints& endpoints, const std::vector<std::string>& services,
                   double timeout_s, const std::vector<std::string>& optional = {});
struct EvaluateArgs {
  std::string robot = "fetch", object = "block";
  std::string world{sim::world_profile_name(sim::kDefaultWorldProfile)};
  std::string actuation = "default";
  int episodes = 100;
  std::uint64_t seed = 424242;  // the held-out episodes' seed (no training run uses it)
  bool json = false;
  bool strict = false;  // refuse, rather than warn, when the served policy's world differs
};
// Warns (strict: refuses, FAILED_PRECONDITION) when a served role was trained on another
// world, robot, object or actuation than the evaluation's.
int evaluate_command(const Endpoints& endpoints, const EvaluateArgs& args);

struct PipelineArgs {
  TrainArgs experts;  // role ignored; applied to approach, manipulate and retract
  TrainArgs choreographer;
  int eval_episodes = 100;           // held-out episodes through the services
  std::uint64_t eval_seed = 424242;  // the held-out episodes' seed (no training run uses it)
  double wait_s = 30;                // for the services to become healthy
  std::string json_out;              // also write the results as JSON here
  std::string expected;  // compare with the figures checked in here (expected_results.h)
};
int pipeline_command(const Endpoints& endpoints, const PipelineArgs& args);

// The arm's controller (--robot-controller): its state, an emergency stop, and clearing a
// stop. An emergency stop is cleared only by repeating its reason (robot status shows it)
// and naming the operator.
// The simulation-to-base transform from touched points (calibrate_command.cpp).
struct CalibrateArgs {
  std::string pairs;  // JSON: {"pairs": [{"sim_m": [...], "base_m": [...]}, ...]}
  std::string config = "deploy/robot/gateway.json";  // copied with the new base_from_sim
  std::string out;                                   // empty: print only
  double max_residual_mm = 5;
};
int calibrate_command(const CalibrateArgs& args);
int robot_status_command(const Endpoints& endpoints, bool json);
int robot_stop_command(const Endpoints& endpoints, const std::string& reason);
int robot_resume_command(const Endpoints& endpoints, const std::string& acknowledged_reason,
                         const std::string& operator_name);

}  // namespace pnp::pnpctl
