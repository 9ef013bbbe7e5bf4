// pnp-bench-faults: the robot gateway under injected faults. The served Panda hierarchy
// (tests/data/panda_block, or --checkpoints DIR) drives the simulated Panda in real time
// for --episodes episodes, each with one seeded fault: a stalled controller, a stalled
// inference answer, a broken reading, a dropped drive stream, an E-stop from the cell, or
// a gateway whose table is configured 3 cm too low while the policy dives. Prints one JSON
// object
// (bench/faults/fault_run.h); exits 1 when a verdict fails: a target outside the
// controller's box taken in, a fault not followed by a held or stopped arm within the
// dead-man time, or fewer episodes completed than asked.

#include <unistd.h>

#include <iostream>

#include "bench/faults/fault_run.h"
#include "common/error.h"
#include "common/seed_flag.h"
#include "common/validate.h"
#include "tools/common/cli.h"

int main(int argc, char** argv) {
  using namespace pnp;
  CLI::App app{"The robot gateway under injected faults, against the controller stand-in",
               "pnp-bench-faults"};
  faults::FaultRunSpec spec;
  spec.checkpoints = PNP_DEFAULT_CHECKPOINTS;
  std::string config_path = PNP_DEFAULT_GATEWAY_CONFIG;
  int stall_ms = static_cast<int>(spec.stall.count());
  bool json = false;
  app.add_option("--episodes", spec.episodes, "episodes, one fault each")->capture_default_str();
  app.add_option("--seed", spec.seed, "the fault plan's seed; episode k plays scene seed + k")
      ->check(pnp::seed_value())
      ->capture_default_str();
  app.add_option("--checkpoints", spec.checkpoints,
                 "directory with {approach,manipulate,retract,hlc}.ckpt (panda, block)")
      ->capture_default_str();
  app.add_option("--config", config_path, "gateway config")->capture_default_str();
  app.add_option("--stall-ms", stall_ms, "how long a stalled controller or inference waits")
      ->capture_default_str();
  app.add_option("--max-call", spec.max_call, "faults fire on calls 1..N of their kind")
      ->capture_default_str();
  app.add_flag("--json", json, "one line of JSON");
  return tools::run_tool(app, argc, argv, [&] {
    require_positive(spec.episodes, "--episodes");
    require_positive(stall_ms, "--stall-ms");
    require_positive(spec.max_call, "--max-call");
    spec.stall = std::chrono::milliseconds(stall_ms);
    spec.config = robot::GatewayConfig::load(config_path);
    spec.work_dir =
        std::filesystem::temp_directory_path() / ("pnp_bench_faults_" + std::to_string(::getpid()));
    struct RemoveDir {
      std::filesystem::path dir;
      ~RemoveDir() { std::filesystem::remove_all(dir); }
    } cleanup{spec.work_dir};
    const nlohmann::json out = faults::run_faults(spec);
    std::cout << (json ? out.dump() : out.dump(2)) << "\n";
    const bool held = out["faults_not_held_within_deadman"].get<int>() == 0;
    const bool inside = out["executed_outside_controller_box"].get<int>() == 0;
    const bool complete = out["episodes_completed"].get<int>() == spec.episodes;
    if (!(held && inside && complete)) {
      throw Error(ErrorCode::kInternal, "a fault verdict failed (see the JSON above)");
    }
  });
}
