#include "security/rpc_access.h"

#include <array>

namespace pnp::security {
namespace {

constexpr RpcRequirement kReader{AccessClass::kReader};
constexpr RpcRequirement kAgent{AccessClass::kAgent};
constexpr RpcRequirement kOperator{AccessClass::kOperator};
constexpr RpcRequirement kRobot{AccessClass::kRobot};
constexpr RpcRequirement kService{AccessClass::kService};
constexpr RpcRequirement kOperatorOrDelegate{AccessClass::kOperator, AccessClass::kDelegate};
constexpr RpcRequirement kAnyone{std::nullopt};  // any authenticated principal

constexpr std::array kTable{
    // Standard services every server registers.
    RpcAccess{"/grpc.health.v1.Health/Check", kReader, false},
    RpcAccess{"/grpc.health.v1.Health/Watch", kReader, false},
    RpcAccess{"/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo", kReader, false},
    // Inference.
    RpcAccess{"/pnp.policy.v1.PolicyService/Predict", kAgent, false},
    RpcAccess{"/pnp.policy.v1.PolicyService/PredictSession", kAgent, false},
    RpcAccess{"/pnp.policy.v1.PolicyService/PromoteCheckpoint", kOperator, true},
    RpcAccess{"/pnp.policy.v1.PolicyService/GetServingStatus", kReader, false},
    RpcAccess{"/pnp.policy.v1.PolicyService/Ping", kReader, false},
    // Simulation.
    RpcAccess{"/pnp.sim.v1.SimulationService/CreateEnv", kAgent, false},
    RpcAccess{"/pnp.sim.v1.SimulationService/Reset", kAgent, false},
    RpcAccess{"/pnp.sim.v1.SimulationService/Step", kAgent, false},
    RpcAccess{"/pnp.sim.v1.SimulationService/ComputeReward", kAgent, false},
    RpcAccess{"/pnp.sim.v1.SimulationService/GetEnvSpec", kReader, false},
    RpcAccess{"/pnp.sim.v1.SimulationService/CloseEnv", kAgent, false},
    RpcAccess{"/pnp.sim.v1.SimulationService/StreamRollout", kAgent, false},
    // Training.
    RpcAccess{"/pnp.train.v1.TrainingService/CreateTrainingRun", kOperator, true},
    RpcAccess{"/pnp.train.v1.TrainingService/GetTrainingRun", kReader, false},
    RpcAccess{"/pnp.train.v1.TrainingService/ListTrainingRuns", kReader, false},
    RpcAccess{"/pnp.train.v1.TrainingService/CancelTrainingRun", kOperator, true},
    RpcAccess{"/pnp.train.v1.TrainingService/WatchTrainingRun", kReader, false},
    RpcAccess{"/pnp.train.v1.TrainingService/GetRunMetrics", kReader, false},
    RpcAccess{"/pnp.train.v1.TrainingService/ListCheckpoints", kReader, false},
    // The robot controller (and its simulated stand-in).
    RpcAccess{"/pnp.robot.v1.RobotControllerService/AcquireLease", kRobot, true},
    RpcAccess{"/pnp.robot.v1.RobotControllerService/ReleaseLease", kRobot, true},
    RpcAccess{"/pnp.robot.v1.RobotControllerService/StreamPoseTargets", kRobot, true},
    RpcAccess{"/pnp.robot.v1.RobotControllerService/GetState", kReader, false},
    RpcAccess{"/pnp.robot.v1.RobotControllerService/Stop", kAnyone, true},
    RpcAccess{"/pnp.robot.v1.RobotControllerService/Resume", kOperator, true},
    RpcAccess{"/pnp.robot.v1.SimulatedSceneService/ResetScene", kRobot, true},
    // The store (pnp-store-server): the platform's servers read as readers and write as
    // services, under their own name (a run's owner, an audit batch's recorder). Not audited
    // here: the operator call that caused a write (create, cancel) is audited by the server
    // it reached, which knows the operator.
    RpcAccess{"/pnp.store.v1.StoreService/CreateRun", kService, false},
    RpcAccess{"/pnp.store.v1.StoreService/GetRun", kReader, false},
    RpcAccess{"/pnp.store.v1.StoreService/ListRuns", kReader, false},
    RpcAccess{"/pnp.store.v1.StoreService/SetRunState", kService, false},
    RpcAccess{"/pnp.store.v1.StoreService/ClaimNextRun", kService, false},
    RpcAccess{"/pnp.store.v1.StoreService/RenewLease", kService, false},
    RpcAccess{"/pnp.store.v1.StoreService/ReleaseRun", kService, false},
    RpcAccess{"/pnp.store.v1.StoreService/CountClaimable", kReader, false},
    RpcAccess{"/pnp.store.v1.StoreService/AddRunWallTime", kService, false},
    RpcAccess{"/pnp.store.v1.StoreService/RecordMetric", kService, false},
    RpcAccess{"/pnp.store.v1.StoreService/ListMetrics", kReader, false},
    RpcAccess{"/pnp.store.v1.StoreService/SaveCheckpoint", kService, false},
    RpcAccess{"/pnp.store.v1.StoreService/LoadCheckpoint", kReader, false},
    RpcAccess{"/pnp.store.v1.StoreService/GetCheckpointInfo", kReader, false},
    RpcAccess{"/pnp.store.v1.StoreService/ListCheckpoints", kReader, false},
    RpcAccess{"/pnp.store.v1.StoreService/LatestCheckpoint", kReader, false},
    // What changes the checkpoint every replica serves is an operator's: imported runs
    // (pnp-import, promoted or not) and promotions, by an operator or by a server carrying
    // out an operator's call it authenticated (pnp-inference's PromoteCheckpoint), recorded
    // as "<operator> via <server>".
    RpcAccess{"/pnp.store.v1.StoreService/ImportFinished", kOperator, true},
    RpcAccess{"/pnp.store.v1.StoreService/Promote", kOperatorOrDelegate, true},
    RpcAccess{"/pnp.store.v1.StoreService/GetPromotion", kReader, false},
    RpcAccess{"/pnp.store.v1.StoreService/ListPromotions", kReader, false},
    RpcAccess{"/pnp.store.v1.StoreService/WatchPromotions", kReader, false},
    RpcAccess{"/pnp.store.v1.StoreService/PruneCheckpoints", kService, false},
    RpcAccess{"/pnp.store.v1.StoreService/CollectGarbage", kOperator, true},
    RpcAccess{"/pnp.store.v1.StoreService/Backup", kOperator, true},
    // The audit trail: servers append (a reader could forge records); operators read it
    // (it names principals and what they sent), and who read it is audited in turn.
    RpcAccess{"/pnp.store.v1.StoreService/AppendAudit", kService, false},
    RpcAccess{"/pnp.store.v1.StoreService/ReadAudit", kOperator, true},
};

}  // namespace

std::span<const RpcAccess> rpc_access_table() {
  return kTable;
}

const RpcAccess* find_rpc_access(std::string_view path) {
  for (const RpcAccess& entry : kTable)
    if (entry.path == path) return &entry;
  return nullptr;
}

}  // namespace pnp::security
