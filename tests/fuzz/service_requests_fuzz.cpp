// Every service's request handling, on arbitrary bytes: the simulation, inference, training
// and robot-controller services run in one in-process server (real handlers over a real
// store and the checked-in Panda hierarchy) and each input becomes one call through real
// stubs. The first byte picks the RPC (low 5 bits) and whether the live handles (an open
// environment batch, the held lease, a run, a checkpoint) replace the ids the bytes carry
// (bit 7), so the fuzzer reaches the handlers' bodies and not only their id checks. The
// rest is the request, parsed as that RPC's message; a stream's messages are each
// prefixed by a 2-byte little-endian length.
//
// The contract: whatever the request, the server answers with a canonical status that a
// refusal chose (never UNKNOWN or INTERNAL, which mean an exception other than a pnp::Error
// escaped a handler), within the deadline, and without a sanitizer finding.
#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <grpcpp/grpcpp.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "arm_sim/controller_stand_in.h"
#include "pnp/policy/v1/policy_service.grpc.pb.h"
#include "pnp/robot/v1/robot_controller.grpc.pb.h"
#include "pnp/sim/v1/sim_service.grpc.pb.h"
#include "pnp/train/v1/train_service.grpc.pb.h"
#include "services/common/server_runtime.h"
#include "services/inference/policy_service.h"
#include "services/robot_sim/simulated_scene_service.h"
#include "services/sim/sim_service.h"
#include "services/train/training_service.h"
#include "store/checkpoint_import.h"
#include "store/run_store.h"
#include "training/run_manager.h"

namespace pnp::fuzz {
namespace {

namespace pv1 = policy::v1;
namespace rv1 = robot::v1;
namespace sv1 = sim::v1;
namespace tv1 = train::v1;

// Generous for a loaded machine; scripts/fuzz gives this target 30 s per input.
constexpr auto kDeadline = std::chrono::seconds(20);
constexpr std::size_t kMaxStreamMessages = 8;

// On stdout: scripts/fuzz closes this target's stderr, where the services log every
// audited call.
[[noreturn]] void fail(const std::string& rpc, const grpc::Status& status) {
  std::printf("fuzz: %s answered %d: %s\n", rpc.c_str(), status.error_code(),
              status.error_message().c_str());
  std::fflush(stdout);
  std::abort();
}

void check(const std::string& rpc, const grpc::Status& status) {
  switch (status.error_code()) {
    case grpc::StatusCode::UNKNOWN:
    case grpc::StatusCode::INTERNAL:
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      fail(rpc, status);
    default:
      return;
  }
}

std::unique_ptr<grpc::ClientContext> context() {
  auto c = std::make_unique<grpc::ClientContext>();
  c->set_deadline(std::chrono::system_clock::now() + kDeadline);
  return c;
}

using Bytes = std::span<const std::uint8_t>;

// The ids a request may carry, replaced by live ones when the input asks.
struct Handles {
  std::string env_id, lease_id;
  std::int64_t run_id = 0, checkpoint_id = 0;
};

void adopt_handles(google::protobuf::Message& message, const Handles& handles, int depth = 0) {
  const auto* descriptor = message.GetDescriptor();
  const auto* reflection = message.GetReflection();
  for (int i = 0; i < descriptor->field_count(); ++i) {
    const auto* field = descriptor->field(i);
    if (field->is_repeated()) continue;
    const std::string& name = field->name();
    if (name == "env_id" && !handles.env_id.empty()) {
      reflection->SetString(&message, field, handles.env_id);
    } else if (name == "lease_id" && !handles.lease_id.empty()) {
      reflection->SetString(&message, field, handles.lease_id);
    } else if (name == "run_id" && field->cpp_type() == field->CPPTYPE_INT64) {
      reflection->SetInt64(&message, field, handles.run_id);
    } else if (name == "checkpoint_id" && field->cpp_type() == field->CPPTYPE_INT64) {
      reflection->SetInt64(&message, field, handles.checkpoint_id);
    } else if (field->cpp_type() == field->CPPTYPE_MESSAGE && depth < 2 &&
               reflection->HasField(message, field)) {
      adopt_handles(*reflection->MutableMessage(&message, field), handles, depth + 1);
    }
  }
}

// A stream's messages: each a 2-byte little-endian length, then that many bytes.
std::vector<std::span<const std::uint8_t>> split_messages(std::span<const std::uint8_t> bytes) {
  std::vector<std::span<const std::uint8_t>> out;
  while (bytes.size() >= 2 && out.size() < kMaxStreamMessages) {
    const std::size_t length =
        std::min<std::size_t>(std::size_t{bytes[0]} | std::size_t{bytes[1]} << 8, bytes.size() - 2);
    out.push_back(bytes.subspan(2, length));
    bytes = bytes.subspan(2 + length);
  }
  return out;
}

class Platform {
 public:
  Platform()
      : dir_(std::filesystem::temp_directory_path() /
             ("pnp_fuzz_services_" + std::to_string(::getpid()))),
        db_(prepare_store(dir_)),
        arm_(lockstep()),
        policy_(db_),
        manager_({db_, "approach", "fuzz", 1}),
        training_(manager_),
        controller_(arm_),
        scene_(arm_),
        runtime_(
            {"127.0.0.1:0", 1 << 20, {&sim_, &policy_, &training_, &controller_, &scene_}, {}}) {
    policy_.reload();
    const auto channel = runtime_.server().InProcessChannel(grpc::ChannelArguments());
    sim_stub_ = sv1::SimulationService::NewStub(channel);
    policy_stub_ = pv1::PolicyService::NewStub(channel);
    train_stub_ = tv1::TrainingService::NewStub(channel);
    robot_stub_ = rv1::RobotControllerService::NewStub(channel);
    scene_stub_ = rv1::SimulatedSceneService::NewStub(channel);
    open_env();
    tv1::CreateTrainingRunRequest run;
    run.set_role(common::v1::ROLE_APPROACH);
    run.set_algorithm(tv1::ALGORITHM_DDPG_HER);
    run.set_robot(common::v1::ROBOT_PANDA);
    run.set_object(common::v1::OBJECT_SHAPE_BLOCK);
    run.set_seed(1);
    run.mutable_stop()->set_max_steps(100);
    tv1::CreateTrainingRunResponse created;
    if (const auto s = train_stub_->CreateTrainingRun(context().get(), run, &created); !s.ok())
      fail("CreateTrainingRun (the harness's run)", s);
    handles_.run_id = created.run().run_id();
    cancel_run(handles_.run_id);
    register_calls();
  }
  ~Platform() {
    runtime_.shutdown(std::chrono::milliseconds(200));
    std::filesystem::remove_all(dir_);
  }
  Platform(const Platform&) = delete;
  Platform& operator=(const Platform&) = delete;

  void call(std::uint8_t selector, std::span<const std::uint8_t> bytes) {
    const std::size_t index = selector & 0x1f;
    if (index >= calls_.size()) return;
    const bool live = (selector & 0x80) != 0;
    if (live) refresh_lease();
    const Handles none;
    calls_[index](bytes, live ? handles_ : none);
  }

 private:
  // One entry per RPC, in the order of the selector's low 5 bits (service_requests_seeds.txt
  // names them). Calls that would leave lasting work undo it: a created batch is closed, a
  // created run cancelled; a closed live batch is reopened, a new lease kept.
  void register_calls() {
    using Sim = sv1::SimulationService::Stub;
    using Policy = pv1::PolicyService::Stub;
    using Train = tv1::TrainingService::Stub;
    using Robot = rv1::RobotControllerService::Stub;
    auto& sim = *sim_stub_;
    auto& policy = *policy_stub_;
    auto& train = *train_stub_;
    auto& robot = *robot_stub_;
    calls_ = {
        [&](Bytes b, const Handles& h) {
          sv1::CreateEnvResponse created;
          if (unary(&Sim::CreateEnv, sim, "CreateEnv", b, h, &created))
            close_env(created.env_id());  // keeps the server's 256 environments free
        },
        [&](Bytes b, const Handles& h) { unary(&Sim::Reset, sim, "Reset", b, h); },
        [&](Bytes b, const Handles& h) { unary(&Sim::Step, sim, "Step", b, h); },
        [&](Bytes b, const Handles& h) { unary(&Sim::ComputeReward, sim, "ComputeReward", b, h); },
        [&](Bytes b, const Handles& h) { unary(&Sim::GetEnvSpec, sim, "GetEnvSpec", b, h); },
        [&](Bytes b, const Handles& h) {
          if (unary(&Sim::CloseEnv, sim, "CloseEnv", b, h) && !h.env_id.empty()) open_env();
        },
        [&](Bytes b, const Handles& h) {
          bidi<sv1::StreamRolloutRequest, sv1::StreamRolloutResponse>(
              [&](grpc::ClientContext* c) { return sim.StreamRollout(c); }, "StreamRollout", b, h);
        },
        [&](Bytes b, const Handles& h) { unary(&Policy::Predict, policy, "Predict", b, h); },
        [&](Bytes b, const Handles& h) {
          bidi<pv1::PredictSessionRequest, pv1::PredictSessionResponse>(
              [&](grpc::ClientContext* c) { return policy.PredictSession(c); }, "PredictSession", b,
              h);
        },
        [&](Bytes b, const Handles& h) {
          unary(&Policy::PromoteCheckpoint, policy, "PromoteCheckpoint", b, h);
        },
        [&](Bytes b, const Handles& h) {
          unary(&Policy::GetServingStatus, policy, "GetServingStatus", b, h);
        },
        [&](Bytes b, const Handles& h) { unary(&Policy::Ping, policy, "Ping", b, h); },
        [&](Bytes b, const Handles& h) {
          tv1::CreateTrainingRunResponse created;
          if (unary(&Train::CreateTrainingRun, train, "CreateTrainingRun", b, h, &created))
            cancel_run(created.run().run_id());  // one input, no lasting work
        },
        [&](Bytes b, const Handles& h) {
          unary(&Train::GetTrainingRun, train, "GetTrainingRun", b, h);
        },
        [&](Bytes b, const Handles& h) {
          unary(&Train::ListTrainingRuns, train, "ListTrainingRuns", b, h);
        },
        [&](Bytes b, const Handles& h) {
          unary(&Train::CancelTrainingRun, train, "CancelTrainingRun", b, h);
        },
        [&](Bytes b, const Handles& h) { watch(b, h); },
        [&](Bytes b, const Handles& h) {
          unary(&Train::GetRunMetrics, train, "GetRunMetrics", b, h);
        },
        [&](Bytes b, const Handles& h) {
          unary(&Train::ListCheckpoints, train, "ListCheckpoints", b, h);
        },
        [&](Bytes b, const Handles& h) {
          rv1::AcquireLeaseResponse acquired;
          if (unary(&Robot::AcquireLease, robot, "AcquireLease", b, h, &acquired))
            handles_.lease_id = acquired.lease_id();
        },
        [&](Bytes b, const Handles& h) {
          unary(&Robot::ReleaseLease, robot, "ReleaseLease", b, h);
        },
        [&](Bytes b, const Handles& h) {
          bidi<rv1::StreamPoseTargetsRequest, rv1::ControllerFeedback>(
              [&](grpc::ClientContext* c) { return robot.StreamPoseTargets(c); },
              "StreamPoseTargets", b, h);
        },
        [&](Bytes b, const Handles& h) { unary(&Robot::GetState, robot, "GetState", b, h); },
        [&](Bytes b, const Handles& h) { unary(&Robot::Stop, robot, "Stop", b, h); },
        [&](Bytes b, const Handles& h) { unary(&Robot::Resume, robot, "Resume", b, h); },
        [&](Bytes b, const Handles& h) {
          unary(&rv1::SimulatedSceneService::Stub::ResetScene, *scene_stub_, "ResetScene", b, h);
        },
    };
  }

  static arm_sim::StandInOptions lockstep() {
    arm_sim::StandInOptions options;
    options.object = sim::ObjectShape::kBlock;
    options.clock = arm_sim::ClockMode::kLockstep;
    return options;
  }

  // A fresh store holding the checked-in Panda hierarchy, promoted.
  std::string prepare_store(const std::filesystem::path& dir) {
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const std::string db = (dir / "pnp.db").string();
    store::RunStore store(db);
    const auto ids = store::import_hierarchy(
        store, std::filesystem::path(PNP_SOURCE_DIR) / "tests/data/panda_block", "panda", "block");
    handles_.checkpoint_id = ids.front();
    return db;
  }

  // Whether the call was made and succeeded (bytes that are not a request make none).
  template <typename Stub, typename Request, typename Response>
  bool unary(grpc::Status (Stub::*method)(grpc::ClientContext*, const Request&, Response*),
             Stub& stub, const std::string& rpc, std::span<const std::uint8_t> bytes,
             const Handles& handles, Response* out = nullptr) {
    Request request;
    if (!request.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) return false;
    adopt_handles(request, handles);
    Response response;
    const auto status = (stub.*method)(context().get(), request, out ? out : &response);
    check(rpc, status);
    return status.ok();
  }

  template <typename Request, typename Response, typename Open>
  void bidi(const Open& open, const std::string& rpc, std::span<const std::uint8_t> bytes,
            const Handles& handles) {
    std::vector<Request> requests;
    for (const auto message : split_messages(bytes)) {
      Request& r = requests.emplace_back();
      if (!r.ParseFromArray(message.data(), static_cast<int>(message.size()))) return;
      adopt_handles(r, handles);
    }
    const auto c = context();
    const auto stream = open(c.get());
    // Answers are drained while requests go out: a server blocked writing one would
    // otherwise never read the next.
    std::thread drain([&] {
      for (Response response; stream->Read(&response);) {
      }
    });
    for (const auto& r : requests)
      if (!stream->Write(r)) break;
    stream->WritesDone();
    drain.join();
    check(rpc, stream->Finish());
  }

  void watch(std::span<const std::uint8_t> bytes, const Handles& handles) {
    tv1::WatchTrainingRunRequest request;
    if (!request.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) return;
    adopt_handles(request, handles);
    const auto c = context();
    const auto reader = train_stub_->WatchTrainingRun(c.get(), request);
    for (tv1::WatchTrainingRunResponse response; reader->Read(&response);) {
    }
    check("WatchTrainingRun", reader->Finish());
  }

  void open_env() {
    sv1::CreateEnvRequest request;
    request.set_robot(common::v1::ROBOT_PANDA);
    request.set_object(common::v1::OBJECT_SHAPE_BLOCK);
    request.set_count(2);
    sv1::CreateEnvResponse response;
    if (const auto s = sim_stub_->CreateEnv(context().get(), request, &response); !s.ok())
      fail("CreateEnv (the harness's batch)", s);
    handles_.env_id = response.env_id();
  }
  void close_env(const std::string& env_id) {
    if (env_id == handles_.env_id) return;
    sv1::CloseEnvRequest request;
    request.set_env_id(env_id);
    sv1::CloseEnvResponse response;
    sim_stub_->CloseEnv(context().get(), request, &response);
  }
  void cancel_run(std::int64_t run_id) {
    tv1::CancelTrainingRunRequest request;
    request.set_run_id(run_id);
    tv1::CancelTrainingRunResponse response;
    train_stub_->CancelTrainingRun(context().get(), request, &response);
  }
  // The lease lapses after 500 ms without targets: take it again when it has.
  void refresh_lease() {
    rv1::AcquireLeaseRequest request;
    request.set_client_name("fuzz");
    rv1::AcquireLeaseResponse response;
    if (robot_stub_->AcquireLease(context().get(), request, &response).ok())
      handles_.lease_id = response.lease_id();
  }

  std::filesystem::path dir_;
  Handles handles_;
  std::string db_;
  arm_sim::ControllerStandIn arm_;
  services::SimServiceImpl sim_;
  services::PolicyServiceImpl policy_;
  training::RunManager manager_;
  services::TrainingServiceImpl training_;
  services::RobotControllerServiceImpl controller_;
  services::SimulatedSceneServiceImpl scene_;
  services::ServerRuntime runtime_;
  std::unique_ptr<sv1::SimulationService::Stub> sim_stub_;
  std::unique_ptr<pv1::PolicyService::Stub> policy_stub_;
  std::unique_ptr<tv1::TrainingService::Stub> train_stub_;
  std::unique_ptr<rv1::RobotControllerService::Stub> robot_stub_;
  std::unique_ptr<rv1::SimulatedSceneService::Stub> scene_stub_;
  std::vector<std::function<void(Bytes, const Handles&)>> calls_;
};

}  // namespace
}  // namespace pnp::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  // libFuzzer's interface is a free function: the platform lives for the whole process.
  static pnp::fuzz::Platform platform;
  platform.call(data[0], std::span<const std::uint8_t>(data + 1, size - 1));
  return 0;
}
