// pnpctl: the platform's command line. Every command talks to the services over gRPC
// (addresses: --sim, --approach, ..., --inference; defaults are the loopback ports
// scripts/run uses). Errors are one line on stderr and a non-zero exit.

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>

#include "clients/pnpctl/commands.h"
#include "clients/pnpctl/endpoints.h"
#include "common/error.h"
#include "common/seed_flag.h"
#include "common/version.h"
#include "services/common/cli_suggestion.h"
#include "services/common/client_logging.h"
#include "store/run_store.h"
#include "training/preset.h"

namespace {

// Flag checks with the project's wording ("expected ..., got ..."): CLI11's own range
// checks print the whole double range.
double parsed_number(const std::string& value) {
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  return end != value.c_str() && *end == '\0' ? v : std::nan("");
}
CLI::Validator positive() {
  return {[](std::string& value) {
            return parsed_number(value) > 0 ? std::string()
                                            : "expected a positive number, got " + value;
          },
          "POSITIVE"};
}
CLI::Validator success_rate() {
  return {[](std::string& value) {
            const double v = parsed_number(value);
            return v > 0 && v <= 1 ? std::string()
                                   : "expected a success rate in (0, 1], got " + value;
          },
          "(0,1]"};
}

using namespace pnp::pnpctl;

constexpr const char* kActuationHelp =
    "how the hand follows actions: mocap (gym's), arm (the Panda's controller) or default (the "
    "robot's own: docs/SIMULATION.md)";

void add_train_options(CLI::App& cmd, TrainArgs& a, bool with_role) {
  if (with_role)
    cmd.add_option("--role", a.role, "approach, manipulate, retract, hlc or e2e")
        ->capture_default_str();
  cmd.add_option("--algo", a.algorithm, "ddpg_her, bc, bc_offline or a3c [by role]");
  cmd.add_option("--robot", a.robot)->capture_default_str();
  cmd.add_option("--object", a.object)->capture_default_str();
  cmd.add_option("--world", a.world, "world profile: paper or gym (docs/SIMULATION.md)")
      ->capture_default_str();
  cmd.add_option("--actuation", a.actuation, kActuationHelp)->capture_default_str();
  cmd.add_option("--seed", a.seed)->check(pnp::seed_value())->capture_default_str();
  std::vector<std::string> presets;
  for (const auto& p : pnp::training::presets()) presets.emplace_back(p.name);
  cmd.add_option("--preset", a.preset,
                 "the configuration unset options take (pnp-train --preset P --show-preset "
                 "prints it); ours+demos uses demonstrations")
      ->check(CLI::IsMember(presets))
      ->capture_default_str();
  // Unset is the preset's value; a typed 0 is refused, never taken as "unset".
  cmd.add_option("--max-steps", a.max_steps, "training env steps cap [preset]")->check(positive());
  cmd.add_option("--target-success", a.target_success, "success to reach twice [preset]")
      ->check(success_rate());
  cmd.add_option("--eval-interval", a.eval_interval, "training steps between evaluations [preset]")
      ->check(positive());
  cmd.add_option("--eval-episodes", a.eval_episodes, "episodes per evaluation [100]")
      ->check(positive());
  cmd.add_option("--updates-per-transition", a.updates_per_transition,
                 "DDPG gradient steps per stored transition");
  cmd.add_option("--hidden", a.hidden, "hidden widths, e.g. 256,256,256")->delimiter(',');
  cmd.add_option("--workers", a.workers, "A3C workers (hlc)")->check(positive());
  cmd.add_flag("--quiet", a.quiet, "no progress bar");
}

}  // namespace

int main(int argc, char** argv) {
  pnp::services::quiet_grpc_logs_unless_asked();
  CLI::App app{"Control the pick-and-place training and inference platform", "pnpctl"};
  app.require_subcommand(1);
  Endpoints endpoints;
  add_endpoint_options(app, endpoints);
  std::function<int()> command;

  TrainArgs train;
  auto* train_cmd = app.add_subcommand("train", "start a training run and follow it");
  add_train_options(*train_cmd, train, true);
  train_cmd->add_option("--parent", train.parent, "fine-tune from this checkpoint id");
  train_cmd->add_option("--prefix", train.prefix, "checkpoint ids of the experts before this one")
      ->delimiter(',');
  train_cmd->add_option("--experts", train.experts, "hlc: approach,manipulate,retract checkpoints")
      ->delimiter(',');
  train_cmd->add_flag("--detach", train.detach, "return once the run is created");
  train_cmd->callback([&] { command = [&] { return train_command(endpoints, train); }; });

  std::int64_t cancel_run = 0;
  std::string cancel_via = "approach";
  auto* cancel_cmd = app.add_subcommand("cancel", "cancel a pending or running training run");
  cancel_cmd->add_option("RUN", cancel_run, "run id")->required();
  cancel_cmd->add_option("--via", cancel_via, "training service to look the run up on")
      ->capture_default_str();
  cancel_cmd->callback(
      [&] { command = [&] { return cancel_command(endpoints, cancel_run, cancel_via); }; });

  std::string role, state;
  int limit = 20;
  bool csv = false;
  auto* runs_cmd = app.add_subcommand("runs", "list training runs, newest first");
  runs_cmd->add_option("--role", role, "one role's runs [all]");
  runs_cmd->add_option("--state", state, "pending, running, succeeded, failed or cancelled");
  runs_cmd->add_option("--limit", limit, "runs per role")->capture_default_str();
  runs_cmd->add_flag("--csv", csv, "comma-separated output");
  runs_cmd->callback(
      [&] { command = [&] { return runs_command(endpoints, role, state, limit, csv); }; });

  std::int64_t run_id = 0;
  std::string metrics_role = "approach";
  auto* metrics_cmd = app.add_subcommand("metrics", "a run's learning curve");
  metrics_cmd->add_option("RUN", run_id, "run id")->required();
  metrics_cmd->add_option("--via", metrics_role, "training service to ask (all share the store)")
      ->capture_default_str();
  metrics_cmd->add_flag("--csv", csv, "comma-separated output");
  metrics_cmd->callback(
      [&] { command = [&] { return metrics_command(endpoints, metrics_role, run_id, csv); }; });

  auto* checkpoints_cmd =
      app.add_subcommand("checkpoints", "list a run's checkpoints (the ids promote takes)");
  checkpoints_cmd->add_option("RUN", run_id, "run id")->required();
  checkpoints_cmd->add_option("--via", metrics_role, "training service to ask")
      ->capture_default_str();
  checkpoints_cmd->add_flag("--csv", csv, "comma-separated output");
  checkpoints_cmd->callback(
      [&] { command = [&] { return checkpoints_command(endpoints, metrics_role, run_id, csv); }; });

  std::string gc_db;
  int gc_keep = pnp::store::RetentionPolicy{}.keep_last;
  bool gc_json = false;
  auto* gc_cmd = app.add_subcommand(
      "gc",
      "delete old checkpoints from a store file (keeps each run's last, best, promoted "
      "and referenced ones)");
  gc_cmd->add_option("--db", gc_db, "the SQLite store [$PNP_DB]")->envname("PNP_DB")->required();
  gc_cmd->add_option("--keep", gc_keep, "checkpoints kept per run besides those")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  gc_cmd->add_flag("--json", gc_json, "machine-readable output");
  gc_cmd->callback([&] { command = [&] { return gc_command(gc_db, gc_keep, gc_json); }; });

  BackupArgs backup;
  auto* backup_cmd = app.add_subcommand(
      "backup",
      "copy the store, consistently, while the servers keep training and serving (the copy "
      "is a store file: serve it with --db)");
  backup_cmd->add_option("FILE", backup.destination, "the new file (never overwritten)")
      ->required();
  auto* backup_db = backup_cmd->add_option("--db", backup.db, "the SQLite store file");
  pnp::services::add_remote_store_flags(*backup_cmd, backup.store, backup_db);
  backup_cmd->add_flag("--json", backup.json, "machine-readable output");
  backup_cmd->callback([&] { command = [&] { return backup_command(backup); }; });

  AuditArgs audit;
  auto* audit_cmd = app.add_subcommand(
      "audit", "who called which operator or robot RPC, and how it ended (a store's audit trail)");
  audit_cmd->add_option("--db", audit.db, "the SQLite store [$PNP_DB]")->envname("PNP_DB");
  // Not exclusive with --db: $PNP_DB may be set where the store server is used (the image).
  pnp::services::add_remote_store_flags(*audit_cmd, audit.store, nullptr);
  audit_cmd->add_option("--since", audit.since,
                        "from this long ago (90s, 15m, 2h, 7d) or this UTC time (2026-12-04, "
                        "2026-12-04T15:30:00Z)");
  audit_cmd->add_option("--limit", audit.limit, "at most this many, the newest")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  audit_cmd->add_flag("--json", audit.json, "one JSON object per line");
  audit_cmd->add_flag("--wide", audit.wide,
                      "whole requests in the table (else cut at 48 characters)");
  audit_cmd->callback([&] { command = [&] { return audit_command(audit); }; });

  std::vector<std::int64_t> plot_runs;
  std::string plot_out = "learning_curves.svg";
  auto* plot_cmd = app.add_subcommand("plot", "draw learning curves as SVG");
  plot_cmd->add_option("RUN", plot_runs, "run ids")->required();
  plot_cmd->add_option("--out", plot_out, "SVG file")->capture_default_str();
  std::string plot_metric = "score";
  plot_cmd
      ->add_option("--metric", plot_metric,
                   "score (what each run's stop rule compares with its target) or success (task "
                   "success)")
      ->check(CLI::IsMember({"score", "success"}))
      ->capture_default_str();
  plot_cmd->add_option("--via", metrics_role, "training service to ask")->capture_default_str();
  plot_cmd->callback([&] {
    command = [&] {
      return plot_command(endpoints, metrics_role, plot_runs, plot_metric, plot_out);
    };
  });

  std::vector<std::int64_t> promote_ids;
  auto* promote_cmd = app.add_subcommand(
      "promote", "serve checkpoints for their roles (several: all at once, one per role)");
  std::vector<std::int64_t> promote_runs;
  auto* promote_checkpoints = promote_cmd->add_option("CHECKPOINT", promote_ids, "checkpoint ids");
  promote_cmd
      ->add_option("--run", promote_runs,
                   "instead: each run's latest checkpoint (a finished run's final model)")
      ->excludes(promote_checkpoints);
  promote_cmd->add_option("--via", metrics_role, "training service to ask about --run")
      ->capture_default_str();
  promote_cmd->callback([&] {
    if (promote_ids.empty() && promote_runs.empty())
      throw CLI::RequiredError("CHECKPOINT or --run");
    command = [&] {
      return promote_runs.empty() ? promote_command(endpoints, promote_ids)
                                  : promote_runs_command(endpoints, promote_runs, metrics_role);
    };
  });

  PredictArgs predict;
  auto* predict_cmd = app.add_subcommand(
      "predict", "ask the inference service what to do (given state, or a sim episode's first)");
  predict_cmd->add_option("--observation", predict.observation, "25 comma-separated values")
      ->delimiter(',');
  predict_cmd->add_option("--goal", predict.goal, "x,y,z in m")->delimiter(',');
  predict_cmd->add_option("--seed", predict.seed, "sim episode seed (without --observation)")
      ->check(pnp::seed_value())
      ->capture_default_str();
  predict_cmd->add_option("--robot", predict.robot)->capture_default_str();
  predict_cmd->add_option("--object", predict.object)->capture_default_str();
  predict_cmd->add_option("--world", predict.world)->capture_default_str();
  predict_cmd->add_option("--actuation", predict.actuation, kActuationHelp)->capture_default_str();
  predict_cmd->callback([&] { command = [&] { return predict_command(endpoints, predict); }; });

  std::vector<std::string> services(std::begin(kAllServices), std::end(kAllServices));
  double timeout_s = 2;
  auto* health_cmd = app.add_subcommand(
      "health",
      "check every service's health (exit 1 if one is not serving; the end-to-end baseline, "
      "which scripts/run does not start, only when named in --only)");
  auto* health_only =
      health_cmd->add_option("--only", services, "services to check")->delimiter(',');
  health_cmd->add_option("--timeout", timeout_s, "seconds per check")->capture_default_str();
  health_cmd->callback([&] {
    command = [&] {
      const std::vector<std::string> optional =
          health_only->count() > 0 ? std::vector<std::string>{} : std::vector<std::string>{"e2e"};
      return health_command(endpoints, services, timeout_s, optional);
    };
  });

  EvaluateArgs evaluate;
  auto* evaluate_cmd = app.add_subcommand(
      "evaluate", "held-out episodes of the served hierarchy through sim and inference");
  evaluate_cmd->add_option("--episodes", evaluate.episodes)->capture_default_str();
  evaluate_cmd->add_option("--seed", evaluate.seed)
      ->check(pnp::seed_value())
      ->capture_default_str();
  evaluate_cmd->add_option("--robot", evaluate.robot)->capture_default_str();
  evaluate_cmd->add_option("--object", evaluate.object)->capture_default_str();
  evaluate_cmd->add_option("--world", evaluate.world, "world profile: paper or gym")
      ->capture_default_str();
  evaluate_cmd->add_option("--actuation", evaluate.actuation, kActuationHelp)
      ->capture_default_str();
  evaluate_cmd->add_flag("--json", evaluate.json);
  evaluate_cmd->add_flag("--strict", evaluate.strict,
                         "refuse when the served policy was trained on another world, robot, "
                         "object or actuation");
  evaluate_cmd->callback([&] { command = [&] { return evaluate_command(endpoints, evaluate); }; });

  PipelineArgs pipeline;
  auto* pipeline_cmd = app.add_subcommand(
      "pipeline",
      "train the three experts (chained), then the choreographer over them, promote, evaluate");
  add_train_options(*pipeline_cmd, pipeline.experts, false);
  pipeline_cmd
      ->add_option("--hlc-max-steps", pipeline.choreographer.max_steps, "choreographer step cap")
      ->check(positive());
  pipeline_cmd->add_option("--hlc-workers", pipeline.choreographer.workers, "A3C workers")
      ->check(positive());
  pipeline_cmd->add_option("--held-out-episodes", pipeline.eval_episodes)->capture_default_str();
  pipeline_cmd->add_option("--held-out-seed", pipeline.eval_seed)
      ->check(pnp::seed_value())
      ->capture_default_str();
  pipeline_cmd->add_option("--wait", pipeline.wait_s, "seconds to wait for the services")
      ->capture_default_str();
  pipeline_cmd->add_option("--json-out", pipeline.json_out, "also write the results as JSON");
  pipeline_cmd->add_option("--expected", pipeline.expected,
                           "compare with the figures docs give for this job "
                           "(docs/results/expected/main_job.json, per GEMM path and commit)");
  pipeline_cmd->callback([&] {
    // The choreographer shares the world, seed, stop rule and output settings.
    TrainArgs& c = pipeline.choreographer;
    const TrainArgs& e = pipeline.experts;
    c.robot = e.robot;
    c.object = e.object;
    c.world = e.world;
    c.actuation = e.actuation;
    c.seed = e.seed;
    c.preset = e.preset;
    c.target_success = e.target_success;
    c.eval_interval = e.eval_interval;
    c.eval_episodes = e.eval_episodes;
    c.quiet = e.quiet;
    command = [&] { return pipeline_command(endpoints, pipeline); };
  });

  auto* robot_cmd = app.add_subcommand("robot", "the arm's controller: status, stop, resume");
  robot_cmd->require_subcommand(1);
  bool robot_json = false;
  auto* robot_status = robot_cmd->add_subcommand("status", "mode, lease, stop and grip point");
  robot_status->add_flag("--json", robot_json, "one JSON object");
  robot_status->callback(
      [&] { command = [&] { return robot_status_command(endpoints, robot_json); }; });
  CalibrateArgs calibrate;
  auto* robot_calibrate = robot_cmd->add_subcommand(
      "calibrate", "the simulation-to-base transform from >= 3 touched table points");
  robot_calibrate
      ->add_option("--pairs", calibrate.pairs,
                   "JSON: {\"pairs\": [{\"sim_m\": [x,y,z], \"base_m\": [x,y,z]}]}")
      ->required();
  robot_calibrate->add_option("--config", calibrate.config, "the gateway config to copy")
      ->capture_default_str();
  robot_calibrate->add_option("--out", calibrate.out,
                              "write the config with this calibration here (else print only)");
  robot_calibrate
      ->add_option("--max-residual-mm", calibrate.max_residual_mm,
                   "refuse to write when a point is further off the fit")
      ->check(CLI::Range(0.1, 100.0))
      ->capture_default_str();
  robot_calibrate->callback([&] { command = [&] { return calibrate_command(calibrate); }; });
  std::string stop_reason;
  auto* robot_stop = robot_cmd->add_subcommand("stop", "emergency-stop the arm (no lease needed)");
  robot_stop->add_option("--reason", stop_reason, "why (what clearing it acknowledges)")
      ->required();
  robot_stop->callback(
      [&] { command = [&] { return robot_stop_command(endpoints, stop_reason); }; });
  std::string ack;
  const char* user = std::getenv("USER");
  std::string operator_name = user ? user : "";
  auto* robot_resume = robot_cmd->add_subcommand(
      "resume", "clear a stop: an emergency stop needs its reason repeated (robot status)");
  robot_resume->add_option("--ack", ack, "the stop's reason, word for word")->required();
  robot_resume->add_option("--operator", operator_name, "who clears it (logged) [$USER]");
  robot_resume->callback(
      [&] { command = [&] { return robot_resume_command(endpoints, ack, operator_name); }; });

  pnp::add_version_flag(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    const std::vector<std::string> args(argv + 1, argv + argc);
    std::fprintf(stderr, "pnpctl: error: %s%s\n", e.what(),
                 pnp::services::suggest_for_unknown(app, args).c_str());
    return 2;
  }
  try {
    apply_endpoints_file(app, endpoints);
    return command();
  } catch (const pnp::Error& e) {
    const std::string message = e.code() == pnp::ErrorCode::kUnavailable
                                    ? with_endpoints_hint(endpoints, e.what())
                                    : std::string(e.what());
    std::fprintf(stderr, "pnpctl: error: %s\n", message.c_str());
    return e.code() == pnp::ErrorCode::kInvalidArgument ? 2 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pnpctl: error: %s\n", e.what());
    return 1;
  }
}
