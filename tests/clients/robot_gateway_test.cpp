// The robot gateway end to end, in process over loopback with real stubs: the controller
// stand-in (lockstep, so episodes run at computer speed with the same physics), the
// inference service serving the checked-in Panda hierarchy, and the gateway's episode
// loop between them.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <thread>
#include <tuple>

#include "arm_sim/arm_actuated_env.h"
#include "clients/robot_gateway/dry_run.h"
#include "clients/robot_gateway/gateway_episode.h"
#include "clients/robot_gateway/gateway_summary.h"
#include "clients/robot_gateway/operator_wait.h"
#include "common/error.h"
#include "services/common/convert.h"
#include "services/common/server_runtime.h"
#include "services/inference/policy_service.h"
#include "services/robot_sim/simulated_scene_service.h"
#include "serving/served_policy.h"
#include "sim/panda_hand.h"
#include "store/run_store.h"
#include "support/checked_in_hierarchy.h"

namespace pnp::gateway {
namespace {

namespace rv1 = robot::v1;
namespace pv1 = policy::v1;

EpisodeOptions episode(std::uint64_t seed) {
  EpisodeOptions options;
  options.seed = seed;
  return options;
}

arm_sim::StandInOptions lockstep() {
  arm_sim::StandInOptions options;
  options.clock = arm_sim::ClockMode::kLockstep;
  options.world = sim::WorldProfile::kPaper;  // the checked-in hierarchy's world
  return options;
}

std::string loopback(int port) {
  return "127.0.0.1:" + std::to_string(port);
}

robot::GatewayConfig panda_config() {
  return robot::GatewayConfig::load(std::filesystem::path(PNP_SOURCE_DIR) / "deploy" / "robot" /
                                    "gateway.json");
}

// A policy service whose sessions answer too late: the gateway's dead-man must trip.
class StalledPolicyService final : public pv1::PolicyService::Service {
 public:
  grpc::Status GetServingStatus(grpc::ServerContext*, const pv1::GetServingStatusRequest*,
                                pv1::GetServingStatusResponse* response) override {
    response->add_roles()->set_world(common::v1::WORLD_GYM);
    response->set_ready(true);
    return grpc::Status::OK;
  }
  grpc::Status PredictSession(
      grpc::ServerContext* context,
      grpc::ServerReaderWriter<pv1::PredictSessionResponse, pv1::PredictSessionRequest>* stream)
      override {
    pv1::PredictSessionRequest request;
    while (stream->Read(&request)) {
      for (int k = 0; k < 50 && !context->IsCancelled(); ++k) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      if (context->IsCancelled()) break;
      stream->Write({});
    }
    return grpc::Status::OK;
  }
};

// A policy service whose sessions answer with a fixed function of the observation (the
// gripper driven at the object, then at the goal once grasped), as a gym-world, arm-
// trained policy: the gateway then plans as the gym world reads actions.
sim::Action pursue(const sim::Observation& o, const sim::Goal& goal) {
  const sim::TaskState s = sim::TaskState::from(o, goal, 0.05);
  const bool holding = sim::is_held(s);
  const Eigen::Vector3d to = holding ? Eigen::Vector3d(goal - s.object) : s.object - s.gripper;
  sim::Action a;
  a.head<3>() = (6.0 * to).cwiseMax(-1.0).cwiseMin(1.0);
  a(3) = (holding || (s.gripper - s.object).norm() < 0.015) ? -1 : 1;
  return a;
}

class PursuingPolicyService final : public pv1::PolicyService::Service {
 public:
  grpc::Status GetServingStatus(grpc::ServerContext*, const pv1::GetServingStatusRequest*,
                                pv1::GetServingStatusResponse* response) override {
    auto* role = response->add_roles();
    role->set_world(common::v1::WORLD_GYM);
    role->set_robot(common::v1::ROBOT_PANDA);
    role->set_actuation(common::v1::ACTUATION_ARM);
    response->set_ready(true);
    return grpc::Status::OK;
  }
  grpc::Status PredictSession(
      grpc::ServerContext*,
      grpc::ServerReaderWriter<pv1::PredictSessionResponse, pv1::PredictSessionRequest>* stream)
      override {
    pv1::PredictSessionRequest request;
    while (stream->Read(&request)) {
      const sim::Observation o = services::from_proto(request.observation(), "observation");
      const sim::Action a = pursue(o, services::from_proto(request.goal(), "goal"));
      pv1::PredictSessionResponse response;
      services::to_proto(a, *response.mutable_prediction()->mutable_action());
      response.mutable_prediction()->set_subtask(common::v1::SUBTASK_APPROACH);
      if (!stream->Write(response)) break;
    }
    return grpc::Status::OK;
  }
};

// A controller whose readings are broken in one way: the gateway must end that episode
// with the reason naming the field, send nothing, and go on to the next episode.
enum class Breakage { kFingerGap, kNanCommanded, kNoObject, kWrongFrame };

class BrokenReadingController final : public rv1::RobotControllerService::Service,
                                      public rv1::SimulatedSceneService::Service {
 public:
  explicit BrokenReadingController(Breakage breakage, double tcp_m = sim::kGripPointFromFlange_m)
      : breakage_(breakage), tcp_m_(tcp_m) {}
  grpc::Status AcquireLease(grpc::ServerContext*, const rv1::AcquireLeaseRequest* request,
                            rv1::AcquireLeaseResponse* response) override {
    holder_ = request->client_name();
    response->set_lease_id("lease");
    return grpc::Status::OK;
  }
  grpc::Status ReleaseLease(grpc::ServerContext*, const rv1::ReleaseLeaseRequest*,
                            rv1::ReleaseLeaseResponse*) override {
    return grpc::Status::OK;
  }
  grpc::Status ResetScene(grpc::ServerContext*, const rv1::ResetSceneRequest*,
                          rv1::ResetSceneResponse* response) override {
    fill(*response->mutable_state(), false);
    response->mutable_goal()->set_x_m(0.5);
    return grpc::Status::OK;
  }
  grpc::Status GetState(grpc::ServerContext*, const rv1::GetStateRequest*,
                        rv1::GetStateResponse* response) override {
    fill(*response->mutable_state(), true);
    response->set_lockstep(true);
    response->set_lease_holder(holder_);
    response->set_tcp_from_flange_m(tcp_m_);
    return grpc::Status::OK;
  }
  grpc::Status StreamPoseTargets(
      grpc::ServerContext*,
      grpc::ServerReaderWriter<rv1::ControllerFeedback, rv1::StreamPoseTargetsRequest>* stream)
      override {
    rv1::StreamPoseTargetsRequest request;
    while (stream->Read(&request)) {
      if (request.has_target()) ++targets;
    }
    return grpc::Status::OK;
  }
  grpc::Status Stop(grpc::ServerContext*, const rv1::StopRequest* request,
                    rv1::StopResponse*) override {
    last_stop_kind = request->kind();
    ++stops;
    return grpc::Status::OK;
  }
  std::atomic<int> targets{0}, stops{0};
  std::atomic<rv1::StopKind> last_stop_kind{rv1::STOP_KIND_UNSPECIFIED};

 private:
  // The reset's reading is whole; the cycle's is broken.
  void fill(rv1::ControllerFeedback& state, bool broken) const {
    state.set_frame_id(broken && breakage_ == Breakage::kWrongFrame ? "world" : "panda_link0");
    state.mutable_measured()->mutable_position()->set_x_m(0.46);
    state.mutable_measured()->mutable_position()->set_z_m(0.2);
    state.mutable_measured()->mutable_orientation()->set_x(1);  // gripper down
    *state.mutable_commanded() = state.measured();
    if (broken && breakage_ == Breakage::kNanCommanded) {
      state.mutable_commanded()->mutable_position()->set_y_m(std::nan(""));
    }
    if (!(broken && breakage_ == Breakage::kNoObject)) {
      state.mutable_object()->mutable_pose()->mutable_position()->set_x_m(0.3);
      state.mutable_object()->mutable_pose()->mutable_orientation()->set_w(1);
    }
    // 5 cm below closed: not a finger gap.
    state.set_gripper_width_m(broken && breakage_ == Breakage::kFingerGap ? -0.05 : 0.04);
    state.set_mode(rv1::CONTROLLER_MODE_IDLE);
  }
  const Breakage breakage_;
  const double tcp_m_;
  std::string holder_;
};

// The real stand-in's service, with GetState made to stall on demand (a paused
// controller process): the stall lasts until the caller gives up or `release()`.
class StallingController final : public rv1::RobotControllerService::Service {
 public:
  explicit StallingController(services::RobotControllerServiceImpl& inner) : inner_(inner) {}
  void stall_next_get_state() { stall_next_ = true; }
  // Blocks until a stalled GetState has started.
  void wait_for_stall() {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return stalled_calls_ > 0; });
  }
  int stalled_calls() {
    std::lock_guard lock(mutex_);
    return stalled_calls_;
  }
  grpc::Status GetState(grpc::ServerContext* context, const rv1::GetStateRequest* request,
                        rv1::GetStateResponse* response) override {
    if (stall_next_.exchange(false)) {
      {
        std::lock_guard lock(mutex_);
        ++stalled_calls_;
      }
      changed_.notify_all();
      while (!context->IsCancelled()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      return {grpc::StatusCode::CANCELLED, "stalled"};
    }
    return inner_.GetState(context, request, response);
  }
  grpc::Status AcquireLease(grpc::ServerContext* c, const rv1::AcquireLeaseRequest* q,
                            rv1::AcquireLeaseResponse* r) override {
    return inner_.AcquireLease(c, q, r);
  }
  grpc::Status ReleaseLease(grpc::ServerContext* c, const rv1::ReleaseLeaseRequest* q,
                            rv1::ReleaseLeaseResponse* r) override {
    return inner_.ReleaseLease(c, q, r);
  }
  grpc::Status StreamPoseTargets(
      grpc::ServerContext* c,
      grpc::ServerReaderWriter<rv1::ControllerFeedback, rv1::StreamPoseTargetsRequest>* s)
      override {
    return inner_.StreamPoseTargets(c, s);
  }
  grpc::Status Stop(grpc::ServerContext* c, const rv1::StopRequest* q,
                    rv1::StopResponse* r) override {
    return inner_.Stop(c, q, r);
  }
  grpc::Status Resume(grpc::ServerContext* c, const rv1::ResumeRequest* q,
                      rv1::ResumeResponse* r) override {
    return inner_.Resume(c, q, r);
  }

 private:
  services::RobotControllerServiceImpl& inner_;
  std::atomic<bool> stall_next_{false};
  std::mutex mutex_;
  std::condition_variable changed_;
  int stalled_calls_ = 0;  // guarded by mutex_
};

class GatewayEndToEnd : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("pnp_gateway_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
    const std::string db = (dir_ / "pnp.db").string();
    {
      store::RunStore store(db);
      testing::promote_checked_in_panda_hierarchy(store);
    }
    arm_ = std::make_unique<arm_sim::ControllerStandIn>(lockstep());
    controller_service_ = std::make_unique<services::RobotControllerServiceImpl>(*arm_);
    scene_service_ = std::make_unique<services::SimulatedSceneServiceImpl>(*arm_);
    controller_server_ = std::make_unique<services::ServerRuntime>(services::ServerConfig{
        "127.0.0.1:0", 1 << 20, {controller_service_.get(), scene_service_.get()}, {}});
    policy_service_ = std::make_unique<services::PolicyServiceImpl>(db);
    policy_server_ = std::make_unique<services::ServerRuntime>(
        services::ServerConfig{"127.0.0.1:0", 4 << 20, {policy_service_.get()}, {}});
    controller_ = link_to(controller_server_->port(), not_interrupted_);
    policy_stub_ = pv1::PolicyService::NewStub(
        grpc::CreateChannel(loopback(policy_server_->port()), grpc::InsecureChannelCredentials()));
  }
  void TearDown() override {
    controller_.reset();
    policy_server_->shutdown(std::chrono::milliseconds(500));
    controller_server_->shutdown(std::chrono::milliseconds(500));
    std::filesystem::remove_all(dir_);
  }

  static std::unique_ptr<ControllerLink> link_to(int port, const std::atomic<bool>& interrupted) {
    return std::make_unique<ControllerLink>(
        grpc::CreateChannel(loopback(port), grpc::InsecureChannelCredentials()), loopback(port),
        std::chrono::milliseconds(5000), interrupted);
  }

  EventLog recorder() {
    return [this](std::string_view event, const nlohmann::json& fields) {
      events_.push_back({std::string(event), fields});
    };
  }
  int count(std::string_view event) const {
    int n = 0;
    for (const auto& [e, fields] : events_) n += e == event ? 1 : 0;
    return n;
  }

  std::filesystem::path dir_;
  std::unique_ptr<arm_sim::ControllerStandIn> arm_;
  std::unique_ptr<services::RobotControllerServiceImpl> controller_service_;
  std::unique_ptr<services::SimulatedSceneServiceImpl> scene_service_;
  std::unique_ptr<services::ServerRuntime> controller_server_;
  std::unique_ptr<services::PolicyServiceImpl> policy_service_;
  std::unique_ptr<services::ServerRuntime> policy_server_;
  std::unique_ptr<ControllerLink> controller_;
  std::unique_ptr<pv1::PolicyService::Stub> policy_stub_;
  std::vector<std::pair<std::string, nlohmann::json>> events_;
  std::atomic<bool> not_interrupted_{false};
};

// The acceptance case: the served policy picks and places through the gateway and the
// simulated controller. Lockstep physics and greedy inference make it deterministic. The
// checked-in hierarchy (paper world, 64 x 64) was trained on a mocap hand; on the arm at
// its datasheet accelerations it succeeds on 7 of these 10 scenes (docs/RELIABILITY.md).
TEST_F(GatewayEndToEnd, PicksAndPlacesThroughTheControllerStandIn) {
  const robot::GatewayConfig config = panda_config();
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  GatewayEpisodeRunner runner(config, *controller_, *policy_stub_, recorder());
  std::vector<EpisodeReport> reports;
  for (std::uint64_t seed = 900; seed < 910; ++seed) {
    reports.push_back(runner.run(episode(seed), not_interrupted_));
  }
  const nlohmann::json summary = summarize(reports);
  EXPECT_GE(summary["successes"].get<int>(), 6) << summary.dump(2);
  for (const EpisodeReport& r : reports) {
    ::testing::Test::RecordProperty("seed_" + std::to_string(r.seed),
                                    std::string(episode_end_name(r.end)));
    EXPECT_TRUE(r.end == EpisodeEnd::kSuccess || r.end == EpisodeEnd::kStepCap)
        << "seed " << r.seed << ": " << episode_end_name(r.end) << " " << r.reason;
    EXPECT_EQ(r.controller_refused, 0) << "seed " << r.seed;
    EXPECT_EQ(r.steps, static_cast<int>(r.cycle_us.size()));
    EXPECT_EQ(r.steps, r.decisions + r.arrival_waits);
    EXPECT_LE(r.decisions, config.max_episode_steps);
    EXPECT_LE(r.arrival_waits, config.max_arrival_wait_periods * r.decisions);
  }
}

// A real arm has no scene reset: the operator places the object and gives the goal
// (pnp-robot-gateway --goal). Such an episode, on the scene a reset put there, plays
// exactly as the episode with the reset (lockstep: bit for bit).
TEST_F(GatewayEndToEnd, AnEpisodeWithAGivenGoalAndNoResetPlaysAsTheResetOne) {
  const robot::GatewayConfig config = panda_config();
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  GatewayEpisodeRunner runner(config, *controller_, *policy_stub_, recorder());
  const EpisodeReport with_reset = runner.run(episode(903), not_interrupted_);
  const auto scene = controller_->reset_scene(903);  // the operator's placing, here
  EpisodeOptions given = episode(903);
  given.reset_scene = false;
  given.goal_base = Eigen::Vector3d(scene.goal().x_m(), scene.goal().y_m(), scene.goal().z_m());
  const EpisodeReport without = runner.run(given, not_interrupted_);
  EXPECT_EQ(episode_end_name(without.end), episode_end_name(with_reset.end)) << without.reason;
  EXPECT_EQ(without.steps, with_reset.steps);
  EXPECT_EQ(without.decisions, with_reset.decisions);
}

// The checked-in hierarchy was trained on the mocap hand: the gateway says so once per run
// (not per episode), and with --strict refuses it before anything moves.
TEST_F(GatewayEndToEnd, WarnsOnceAboutAMocapTrainedPolicyAndStrictRefusesIt) {
  const robot::GatewayConfig config = panda_config();
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  GatewayEpisodeRunner runner(config, *controller_, *policy_stub_, recorder());
  runner.run(episode(900), not_interrupted_);
  runner.run(episode(901), not_interrupted_);
  ASSERT_EQ(count("policy_warning"), 1);
  for (const auto& [event, fields] : events_) {
    if (event != "policy_warning") continue;
    EXPECT_NE(fields["reason"].get<std::string>().find("trained on the mocap hand"),
              std::string::npos)
        << fields.dump();
  }
  const std::uint64_t sequence = arm_->state().sequence;
  GatewayEpisodeRunner strict(config, *controller_, *policy_stub_, recorder(), true);
  try {
    strict.run(episode(902), not_interrupted_);
    FAIL() << "a mocap-trained policy drove the arm under --strict";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
    EXPECT_NE(std::string(e.what()).find("(--strict)"), std::string::npos) << e.what();
  }
  EXPECT_EQ(arm_->state().sequence, sequence);  // nothing was sent
}

// Simulation that predicts the robot: the arm-actuated world plays an episode exactly as
// the gateway plays it on the lockstep controller, step for step and bit for bit (the
// same planning, the same controller intake, the same arm, the same observation), with
// the same served policy; the gateway only stops early, on success. The gateway here is
// the real one, over gRPC, with the inference service between it and the policy.
TEST_F(GatewayEndToEnd, TheArmActuatedWorldPlaysWhatTheGatewayPlaysBitForBit) {
  const robot::GatewayConfig config = panda_config();
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  std::shared_ptr<const serving::ServedPolicy> served;
  {
    store::RunStore store((dir_ / "pnp.db").string());
    served = serving::load_promoted(store, store.promotions(), serving::PolicyKind::kHierarchy);
  }
  arm_sim::ArmActuatedEnv env(
      sim::WorldModel::load(sim::Robot::kPanda, sim::ObjectShape::kBlock, lockstep().world));
  int compared = 0, successes = 0;
  for (std::uint64_t seed = 900; seed < 905; ++seed) {
    events_.clear();
    EpisodeOptions traced = episode(seed);
    traced.trace = true;
    const EpisodeReport report =
        GatewayEpisodeRunner(config, *controller_, *policy_stub_, recorder())
            .run(traced, not_interrupted_);
    ASSERT_EQ(report.refused + report.controller_refused + report.held_without_target, 0)
        << "seed " << seed << ": a hold would let lockstep time stand still";
    successes += report.success ? 1 : 0;
    std::vector<nlohmann::json> cycles;
    for (const auto& [event, fields] : events_)
      if (event == "cycle") cycles.push_back(fields);
    ASSERT_EQ(static_cast<int>(cycles.size()), report.decisions) << seed;

    sim::Observation observation = env.reset(seed);
    const serving::ServedPolicy::Lease controller = served->acquire();
    for (const nlohmann::json& cycle : cycles) {
      for (std::size_t k = 0; k < 3; ++k) {
        const auto i = static_cast<Eigen::Index>(k);
        ASSERT_EQ(observation(sim::obs::kGripperPos + i), cycle["grip_sim_m"][k].get<double>())
            << "seed " << seed << " step " << cycle["step"] << " axis " << k;
        ASSERT_EQ(observation(sim::obs::kObjectPos + i), cycle["object_sim_m"][k].get<double>())
            << "seed " << seed << " step " << cycle["step"];
      }
      const serving::Decision decision = controller->act(observation, env.episode_goal());
      for (std::size_t k = 0; k < sim::kActionSize; ++k)
        ASSERT_EQ(decision.action(static_cast<Eigen::Index>(k)), cycle["action"][k].get<double>())
            << "seed " << seed;
      observation =
          env.step(decision.action, env.episode_goal(), sim::Objective::kTask).observation;
      ++compared;
    }
    // Where the gateway stopped on success, the world has the object at the goal too.
    EXPECT_EQ(report.success,
              sim::is_task_success(sim::object_position(observation), env.episode_goal()))
        << seed;
  }
  EXPECT_GT(compared, 100);
  EXPECT_GT(successes, 0);
}

// The same in the gym world, whose actions move the measured grip point (the planning
// path the paper world does not take), with a policy that is a function of the
// observation, served by a stand-in policy service.
TEST(ArmActuatedWorld, PlaysWhatTheGatewayPlaysInTheGymWorldBitForBit) {
  arm_sim::StandInOptions options;
  options.clock = arm_sim::ClockMode::kLockstep;
  options.world = sim::WorldProfile::kGym;
  arm_sim::ControllerStandIn arm(options);
  services::RobotControllerServiceImpl controller_service(arm);
  services::SimulatedSceneServiceImpl scene_service(arm);
  services::ServerRuntime controller_server(
      services::ServerConfig{"127.0.0.1:0", 1 << 20, {&controller_service, &scene_service}, {}});
  PursuingPolicyService policy_service;
  services::ServerRuntime policy_server(
      services::ServerConfig{"127.0.0.1:0", 1 << 20, {&policy_service}, {}});
  std::atomic<bool> not_interrupted{false};
  ControllerLink link(
      grpc::CreateChannel(loopback(controller_server.port()), grpc::InsecureChannelCredentials()),
      loopback(controller_server.port()), std::chrono::milliseconds(5000), not_interrupted);
  auto policy = pv1::PolicyService::NewStub(
      grpc::CreateChannel(loopback(policy_server.port()), grpc::InsecureChannelCredentials()));
  link.acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  std::vector<nlohmann::json> cycles;
  const EventLog log = [&](std::string_view event, const nlohmann::json& fields) {
    if (event == "cycle") cycles.push_back(fields);
  };
  arm_sim::ArmActuatedEnv env(
      sim::WorldModel::load(sim::Robot::kPanda, sim::ObjectShape::kBlock, options.world));
  const robot::GatewayConfig config = panda_config();
  int compared = 0;
  for (std::uint64_t seed = 910; seed < 913; ++seed) {
    cycles.clear();
    EpisodeOptions traced = episode(seed);
    traced.trace = true;
    const EpisodeReport report =
        GatewayEpisodeRunner(config, link, *policy, log).run(traced, not_interrupted);
    ASSERT_EQ(report.refused + report.controller_refused + report.held_without_target, 0) << seed;
    ASSERT_EQ(static_cast<int>(cycles.size()), report.decisions) << seed;
    sim::Observation observation = env.reset(seed);
    for (const nlohmann::json& cycle : cycles) {
      for (std::size_t k = 0; k < 3; ++k) {
        ASSERT_EQ(observation(sim::obs::kGripperPos + static_cast<Eigen::Index>(k)),
                  cycle["grip_sim_m"][k].get<double>())
            << "seed " << seed << " step " << cycle["step"];
      }
      ASSERT_EQ(sim::finger_gap(observation), cycle["gripper_width_m"].get<double>());
      observation = env.step(pursue(observation, env.episode_goal()), env.episode_goal(),
                             sim::Objective::kTask)
                        .observation;
      ++compared;
    }
  }
  EXPECT_GT(compared, 60);
  policy_server.shutdown(std::chrono::milliseconds(500));
  controller_server.shutdown(std::chrono::milliseconds(500));
}

// The arm lags the policy's mocap-trained expectation, so the gateway waits for it: after
// a target, the policy is asked again only once the grip point is within the tolerance
// of it, or after max_arrival_wait_periods periods of waiting; never before the first
// target. Without waits (0) every cycle asks the policy.
TEST_F(GatewayEndToEnd, WaitsForTheArmToReachATargetBeforeAskingAgain) {
  robot::GatewayConfig config = panda_config();
  config.max_arrival_wait_periods = 3;
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  EpisodeOptions traced = episode(903);
  traced.trace = true;
  const EpisodeReport waited = GatewayEpisodeRunner(config, *controller_, *policy_stub_, recorder())
                                   .run(traced, not_interrupted_);
  EXPECT_GT(waited.arrival_waits, 0);
  EXPECT_EQ(waited.steps, waited.decisions + waited.arrival_waits);
  int in_a_row = 0;
  bool asked = false;
  for (const auto& [event, fields] : events_) {
    if (event == "cycle") {
      asked = true;
      in_a_row = 0;
    } else if (event == "arrival_wait") {
      EXPECT_TRUE(asked) << "waited before the first target";
      EXPECT_LE(++in_a_row, config.max_arrival_wait_periods);
      EXPECT_GT(fields["distance_m"].get<double>(), config.arrival_tolerance_m);
    }
  }

  config.max_arrival_wait_periods = 0;
  const EpisodeReport every_period =
      GatewayEpisodeRunner(config, *controller_, *policy_stub_, recorder())
          .run(episode(903), not_interrupted_);
  EXPECT_EQ(every_period.arrival_waits, 0);
  EXPECT_EQ(every_period.steps, every_period.decisions);
}

// A hold that cannot be delivered ends the episode on that cycle: here the arm is
// emergency-stopped just before a wait cycle sends its target again, and the controller's
// refusal of that re-send is the episode's end (no further cycle reads the state).
TEST_F(GatewayEndToEnd, AHoldTheControllerRefusesEndsTheEpisodeThere) {
  robot::GatewayConfig config = panda_config();
  config.max_arrival_wait_periods = 3;
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  int wait_step = -1;
  EventLog log = [&](std::string_view event, const nlohmann::json& fields) {
    events_.push_back({std::string(event), fields});
    if (event == "arrival_wait" && wait_step < 0) {
      wait_step = fields["step"].get<int>();
      arm_->stop("a person walked into the cell", robot::StopKind::kEmergency);
    }
  };
  EpisodeOptions traced = episode(903);
  traced.trace = true;
  const EpisodeReport report =
      GatewayEpisodeRunner(config, *controller_, *policy_stub_, log).run(traced, not_interrupted_);
  ASSERT_GE(wait_step, 0) << "no cycle waited for the arm";
  EXPECT_EQ(report.end, EpisodeEnd::kStopped);
  // With the stop's reason as the controller reports it: what an operator acknowledges.
  EXPECT_EQ(report.reason,
            "the controller refused a target: the arm is stopped (STOP_KIND_EMERGENCY: a person "
            "walked into the cell)");
  EXPECT_EQ(report.steps, wait_step);  // the failed cycle is the last
  EXPECT_EQ(report.arrival_waits, 1);
}

// A dry run plays the episode on a shadow of the arm started where the live arm is, and
// sends the live arm nothing; what it records is what the live run then sends, target by
// target (both arms are the same simulated Panda in lockstep here).
TEST_F(GatewayEndToEnd, ADryRunsRecordIsWhatTheLiveRunSends) {
  const robot::GatewayConfig config = panda_config();
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  using Record = std::vector<std::pair<int, robot::PoseTarget>>;
  const auto recording = [](Record& into) {
    return [&into](std::uint64_t, int step, const robot::PoseTarget& t) {
      into.emplace_back(step, t);
    };
  };
  Record dry_record, live_record;
  EpisodeOptions options = episode(903);
  options.record = recording(dry_record);
  const EpisodeReport dry = DryRun(config, robot::ControllerLimits{}, *controller_, *policy_stub_,
                                   recorder(), false, not_interrupted_)
                                .run(options, not_interrupted_);
  EXPECT_EQ(arm_->state().sequence, 0u);  // no target ever reached the live controller
  EXPECT_EQ(dry.arm_left, "untouched (dry run)");
  ASSERT_GT(dry_record.size(), 10u);

  options.record = recording(live_record);
  const EpisodeReport live = GatewayEpisodeRunner(config, *controller_, *policy_stub_, recorder())
                                 .run(options, not_interrupted_);
  EXPECT_EQ(dry.end, live.end) << dry.reason << " / " << live.reason;
  EXPECT_EQ(dry.steps, live.steps);
  ASSERT_EQ(dry_record.size(), live_record.size());
  for (std::size_t k = 0; k < dry_record.size(); ++k) {
    const auto& [dry_step, d] = dry_record[k];
    const auto& [live_step, l] = live_record[k];
    EXPECT_EQ(dry_step, live_step);
    EXPECT_EQ(d.pose.position_m, l.pose.position_m) << "target " << k;
    EXPECT_EQ(d.pose.orientation.coeffs(), l.pose.orientation.coeffs()) << "target " << k;
    EXPECT_EQ(d.gripper_width_m, l.gripper_width_m) << "target " << k;
  }
}

// An emergency-stopped live arm: the dry run does not start, and ends the run as a live
// run would (an operator must clear the stop first).
TEST_F(GatewayEndToEnd, ADryRunOnAnEmergencyStoppedArmEndsTheRun) {
  const robot::GatewayConfig config = panda_config();
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  arm_->stop("a person walked into the cell", robot::StopKind::kEmergency);
  const EpisodeReport report = DryRun(config, robot::ControllerLimits{}, *controller_,
                                      *policy_stub_, recorder(), false, not_interrupted_)
                                   .run(episode(903), not_interrupted_);
  EXPECT_EQ(report.end, EpisodeEnd::kStopped);
  EXPECT_TRUE(ends_run(report.end));
  EXPECT_NE(report.reason.find("a person walked into the cell"), std::string::npos)
      << report.reason;
  EXPECT_EQ(report.steps, 0);
}

// The live arm must hold while the shadow plays: stopped meanwhile, the dry run's episode
// ends there with the reason.
TEST_F(GatewayEndToEnd, ADryRunEndsWhenTheLiveArmIsStopped) {
  const robot::GatewayConfig config = panda_config();
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  EventLog log = [this](std::string_view event, const nlohmann::json& fields) {
    events_.push_back({std::string(event), fields});
    if (event == "cycle" && fields["step"] == 5)
      arm_->stop("a person walked into the cell", robot::StopKind::kEmergency);
  };
  EpisodeOptions options = episode(903);
  options.trace = true;
  const EpisodeReport report = DryRun(config, robot::ControllerLimits{}, *controller_,
                                      *policy_stub_, log, false, not_interrupted_)
                                   .run(options, not_interrupted_);
  EXPECT_EQ(report.end, EpisodeEnd::kStopped);
  EXPECT_NE(report.reason.find("dry run: the live arm was stopped"), std::string::npos)
      << report.reason;
  EXPECT_NE(report.reason.find("a person walked into the cell"), std::string::npos);
  EXPECT_EQ(report.steps, 6);
  EXPECT_EQ(arm_->state().sequence, 0u);
}

// The trace is opt-in: one "cycle" event per cycle that planned a target and one
// "arrival_wait" event per cycle that waited for the arm, in step order, with the grip
// point, the object, the action and the subtask the policy chose.
TEST_F(GatewayEndToEnd, TraceLogsEveryCycleOnlyWhenAskedFor) {
  const robot::GatewayConfig config = panda_config();
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  GatewayEpisodeRunner runner(config, *controller_, *policy_stub_, recorder());
  const EpisodeReport quiet = runner.run(episode(902), not_interrupted_);
  EXPECT_EQ(count("cycle"), 0);
  EpisodeOptions traced = episode(902);
  traced.trace = true;
  const EpisodeReport report = runner.run(traced, not_interrupted_);
  EXPECT_EQ(report.steps, quiet.steps);  // lockstep and greedy: the same episode
  ASSERT_EQ(report.refused, 0);          // a refused cycle logs "refused" instead
  ASSERT_EQ(count("cycle"), report.decisions);
  ASSERT_EQ(count("arrival_wait"), report.arrival_waits);
  int expected_step = 0;
  for (const auto& [event, fields] : events_) {
    if (event == "arrival_wait") {
      EXPECT_EQ(fields["step"].get<int>(), expected_step++);
    }
    if (event != "cycle") continue;
    EXPECT_EQ(fields["step"].get<int>(), expected_step++);
    EXPECT_EQ(fields["object_sim_m"].size(), 3u);
    EXPECT_EQ(fields["grip_sim_m"].size(), 3u);
    EXPECT_EQ(fields["action"].size(), 4u);
    const int subtask = fields["subtask"].get<int>();
    EXPECT_TRUE(subtask >= 1 && subtask <= 3) << subtask;  // approach, manipulate, retract
  }
}

TEST_F(GatewayEndToEnd, InterruptEmergencyStopsTheArmAndEndsTheRun) {
  std::atomic<bool> interrupted{false};
  auto link = link_to(controller_server_->port(), interrupted);
  link->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  interrupted = true;  // Ctrl-C before the first cycle (a call under way would be cancelled)
  const robot::GatewayConfig config = panda_config();
  GatewayEpisodeRunner runner(config, *link, *policy_stub_, recorder());
  const EpisodeReport report = runner.run(episode(902), interrupted);
  EXPECT_EQ(report.end, EpisodeEnd::kInterrupted);
  EXPECT_TRUE(ends_run(report.end));
  EXPECT_EQ(report.arm_left, "emergency_stop");
  EXPECT_EQ(arm_->state().arm.mode, arm_sim::ArmMode::kStopped);
  EXPECT_EQ(arm_->state().stop_kind, robot::StopKind::kEmergency);
}

// Ctrl-C while the runner still waits for an inference service that is not up (before the
// first cycle): the episode ends interrupted and the arm is emergency-stopped, rather than
// the wait's cancellation escaping the runner and leaving the arm as it was.
TEST_F(GatewayEndToEnd, InterruptWhileWaitingForInferenceStillEmergencyStopsTheArm) {
  std::atomic<bool> interrupted{false};
  auto link = link_to(controller_server_->port(), interrupted);
  link->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  auto unreachable = pv1::PolicyService::NewStub(
      grpc::CreateChannel("127.0.0.1:1", grpc::InsecureChannelCredentials()));
  interrupted = true;
  const robot::GatewayConfig config = panda_config();
  GatewayEpisodeRunner runner(config, *link, *unreachable, recorder());
  const EpisodeReport report = runner.run(episode(904), interrupted);
  EXPECT_EQ(report.end, EpisodeEnd::kInterrupted);
  EXPECT_NE(report.reason.find("waiting for the inference service"), std::string::npos)
      << report.reason;
  EXPECT_EQ(report.steps, 0);
  EXPECT_EQ(report.arm_left, "emergency_stop");
  EXPECT_EQ(arm_->state().stop_kind, robot::StopKind::kEmergency);
}

TEST_F(GatewayEndToEnd, StalledInferenceHoldsTheArmAndEndsTheEpisode) {
  StalledPolicyService stalled;
  services::ServerRuntime stalled_server({"127.0.0.1:0", 1 << 20, {&stalled}, {}});
  auto stub = pv1::PolicyService::NewStub(
      grpc::CreateChannel(loopback(stalled_server.port()), grpc::InsecureChannelCredentials()));
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  const robot::GatewayConfig config = panda_config();
  GatewayEpisodeRunner runner(config, *controller_, *stub, recorder());
  const auto before = arm_->state();
  const EpisodeReport report = runner.run(episode(903), not_interrupted_);
  EXPECT_EQ(report.end, EpisodeEnd::kDeadman);
  EXPECT_FALSE(ends_run(report.end));
  EXPECT_NE(report.reason.find("inference did not answer"), std::string::npos) << report.reason;
  EXPECT_EQ(report.steps, 0);
  // Nothing was sent (no older pose was replayed) and the arm was stopped protectively.
  const auto after = arm_->state();
  EXPECT_EQ(after.sequence, 0u);
  EXPECT_LT((after.arm.commanded_base.position_m - before.arm.commanded_base.position_m).norm(),
            1e-9);
  EXPECT_EQ(report.arm_left, "protective_stop");
  EXPECT_EQ(after.stop_kind, robot::StopKind::kProtective);
  EXPECT_EQ(count("deadman"), 1);
  stalled_server.shutdown(std::chrono::milliseconds(100));
}

// A policy service that answers but serves nothing yet.
class UnreadyPolicyService final : public pv1::PolicyService::Service {
 public:
  grpc::Status GetServingStatus(grpc::ServerContext*, const pv1::GetServingStatusRequest*,
                                pv1::GetServingStatusResponse* response) override {
    response->set_ready(false);
    return grpc::Status::OK;
  }
};

// Without a served policy there is no world to read actions in: the episode is refused
// before the arm moves, whether the service serves nothing or cannot say.
TEST_F(GatewayEndToEnd, NoServedPolicyIsRefusedBeforeTheArmMoves) {
  UnreadyPolicyService unready;
  pv1::PolicyService::Service unimplemented;  // GetServingStatus: UNIMPLEMENTED
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  const robot::GatewayConfig config = panda_config();
  for (auto [service, code, message] :
       {std::tuple<pv1::PolicyService::Service*, ErrorCode, std::string>{
            &unready, ErrorCode::kFailedPrecondition, "serves no whole policy yet"},
        {&unimplemented, ErrorCode::kUnavailable, "GetServingStatus failed"}}) {
    services::ServerRuntime server({"127.0.0.1:0", 1 << 20, {service}, {}});
    auto stub = pv1::PolicyService::NewStub(
        grpc::CreateChannel(loopback(server.port()), grpc::InsecureChannelCredentials()));
    GatewayEpisodeRunner runner(config, *controller_, *stub, recorder());
    const auto before = arm_->state();
    try {
      runner.run(episode(904), not_interrupted_);
      ADD_FAILURE() << "ran without a served policy";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), code);
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
    EXPECT_EQ(arm_->state().sequence, before.sequence);
    server.shutdown(std::chrono::milliseconds(100));
  }
}

class BrokenReadings : public GatewayEndToEnd,
                       public ::testing::WithParamInterface<std::pair<Breakage, std::string>> {};

TEST_P(BrokenReadings, EndOnlyThatEpisodeWithTheFieldNamed) {
  const auto& [breakage, field] = GetParam();
  BrokenReadingController broken(breakage);
  services::ServerRuntime broken_server(
      {"127.0.0.1:0",
       1 << 20,
       {static_cast<rv1::RobotControllerService::Service*>(&broken),
        static_cast<rv1::SimulatedSceneService::Service*>(&broken)},
       {}});
  auto link = link_to(broken_server.port(), not_interrupted_);
  link->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  const robot::GatewayConfig config = panda_config();
  GatewayEpisodeRunner runner(config, *link, *policy_stub_, recorder());
  for (std::uint64_t seed : {1u, 2u}) {  // the second episode runs as well
    const EpisodeReport report = runner.run(episode(seed), not_interrupted_);
    EXPECT_EQ(report.end, EpisodeEnd::kControllerFault);
    EXPECT_NE(report.reason.find(field), std::string::npos) << report.reason;
    EXPECT_EQ(report.steps, 0);
    EXPECT_EQ(report.arm_left, "protective_stop");
  }
  EXPECT_EQ(broken.targets.load(), 0);  // nothing was sent
  EXPECT_EQ(broken.stops.load(), 2);
  EXPECT_EQ(broken.last_stop_kind.load(), rv1::STOP_KIND_PROTECTIVE);
  EXPECT_EQ(count("bad_reading"), 2);
  broken_server.shutdown(std::chrono::milliseconds(100));
}

INSTANTIATE_TEST_SUITE_P(
    EveryBreakage, BrokenReadings,
    ::testing::Values(std::pair{Breakage::kFingerGap, std::string("finger_gap_m")},
                      std::pair{Breakage::kNanCommanded, std::string("commanded.position")},
                      std::pair{Breakage::kNoObject, std::string("no perception of the object")},
                      std::pair{Breakage::kWrongFrame, std::string("frame_id")}));

TEST_F(GatewayEndToEnd, AControllerTrackingAnotherGripPointIsRefusedBeforeAnythingMoves) {
  BrokenReadingController franka_default(Breakage::kFingerGap, 0.1034);
  services::ServerRuntime server(
      {"127.0.0.1:0",
       1 << 20,
       {static_cast<rv1::RobotControllerService::Service*>(&franka_default),
        static_cast<rv1::SimulatedSceneService::Service*>(&franka_default)},
       {}});
  auto link = link_to(server.port(), not_interrupted_);
  link->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  const robot::GatewayConfig config = panda_config();
  GatewayEpisodeRunner runner(config, *link, *policy_stub_, recorder());
  try {
    runner.run(episode(5), not_interrupted_);
    ADD_FAILURE() << "drove a controller with another TCP";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
    EXPECT_NE(std::string(e.what()).find("0.1034"), std::string::npos) << e.what();
  }
  EXPECT_EQ(franka_default.targets.load(), 0);
  server.shutdown(std::chrono::milliseconds(100));
}

// A paused controller: GetState does not answer. The episode ends within the dead-man
// time as a dead-man, and the next episode runs.
TEST_F(GatewayEndToEnd, AStalledControllerEndsTheEpisodeAndTheRunGoesOn) {
  StallingController stalling(*controller_service_);
  services::ServerRuntime server(
      {"127.0.0.1:0",
       1 << 20,
       {static_cast<rv1::RobotControllerService::Service*>(&stalling), scene_service_.get()},
       {}});
  auto link = link_to(server.port(), not_interrupted_);
  link->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  const robot::GatewayConfig config = panda_config();
  EventLog log = recorder();
  int cycles = 0;
  GatewayEpisodeRunner runner(config, *link, *policy_stub_,
                              [&](std::string_view event, const nlohmann::json& fields) {
                                if (event == "episode_start" && cycles++ == 0) {
                                  stalling.stall_next_get_state();  // the first cycle's read
                                }
                                log(event, fields);
                              });
  const EpisodeReport stalled = runner.run(episode(905), not_interrupted_);
  EXPECT_EQ(stalled.end, EpisodeEnd::kDeadman);
  EXPECT_NE(stalled.reason.find("GetState"), std::string::npos) << stalled.reason;
  EXPECT_EQ(stalling.stalled_calls(), 1);
  EXPECT_EQ(stalled.arm_left, "protective_stop");
  const EpisodeReport next = runner.run(episode(906), not_interrupted_);
  EXPECT_TRUE(next.end == EpisodeEnd::kSuccess || next.end == EpisodeEnd::kStepCap)
      << episode_end_name(next.end) << ": " << next.reason;
  EXPECT_GT(next.steps, 0);
  EXPECT_EQ(count("protective_stop_cleared"), 1);
  server.shutdown(std::chrono::milliseconds(100));
}

// Ctrl-C while the controller stalls: the wait gives way at once (the stalled call is
// cancelled, not waited out) and the arm is emergency-stopped.
TEST_F(GatewayEndToEnd, InterruptDuringAStallStopsTheArm) {
  StallingController stalling(*controller_service_);
  services::ServerRuntime server(
      {"127.0.0.1:0",
       1 << 20,
       {static_cast<rv1::RobotControllerService::Service*>(&stalling), scene_service_.get()},
       {}});
  std::atomic<bool> interrupted{false};
  auto link = link_to(server.port(), interrupted);
  link->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  // The link's own wait, with a deadline far beyond the test's life: only the interrupt
  // can end it.
  stalling.stall_next_get_state();
  std::jthread operator_thread([&] {
    stalling.wait_for_stall();
    interrupted.store(true);
  });
  try {
    link->state(std::chrono::minutes(10));
    ADD_FAILURE() << "the stalled call returned without the interrupt";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kCancelled) << e.what();
  }
  operator_thread.join();
  // Through the runner: the cycle's stalled read ends as an interruption and an E-stop.
  interrupted.store(false);
  const robot::GatewayConfig config = panda_config();
  EventLog log = recorder();
  std::jthread interrupter;
  GatewayEpisodeRunner runner(config, *link, *policy_stub_,
                              [&](std::string_view event, const nlohmann::json& fields) {
                                if (event == "episode_start") {
                                  stalling.stall_next_get_state();
                                  interrupter = std::jthread([&] {
                                    while (stalling.stalled_calls() < 2) std::this_thread::yield();
                                    interrupted.store(true);
                                  });
                                }
                                log(event, fields);
                              });
  const EpisodeReport report = runner.run(episode(907), interrupted);
  interrupter.join();
  EXPECT_EQ(report.end, EpisodeEnd::kInterrupted) << report.reason;
  EXPECT_EQ(report.arm_left, "emergency_stop");
  EXPECT_EQ(arm_->state().stop_kind, robot::StopKind::kEmergency);
  server.shutdown(std::chrono::milliseconds(100));
}

// Someone else's E-stop ends the run; the gateway cannot clear it, an operator can.
TEST_F(GatewayEndToEnd, AnEmergencyStopEndsTheRunUntilAnOperatorClearsIt) {
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  const robot::GatewayConfig config = panda_config();
  GatewayEpisodeRunner runner(config, *controller_, *policy_stub_, recorder());
  arm_->stop("a person walked into the cell", robot::StopKind::kEmergency);
  const EpisodeReport report = runner.run(episode(908), not_interrupted_);
  EXPECT_EQ(report.end, EpisodeEnd::kStopped);
  EXPECT_TRUE(ends_run(report.end));
  EXPECT_NE(report.reason.find("a person walked into the cell"), std::string::npos);
  EXPECT_EQ(arm_->state().sequence, 0u);
  try {
    controller_->clear_protective_stop();
    ADD_FAILURE() << "the lease holder cleared an emergency stop";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("operator_name"), std::string::npos) << e.what();
  }
  arm_->resume({"", "a person walked into the cell", "ops"});
  const EpisodeReport after = runner.run(episode(908), not_interrupted_);
  EXPECT_TRUE(after.end == EpisodeEnd::kSuccess || after.end == EpisodeEnd::kStepCap)
      << episode_end_name(after.end) << ": " << after.reason;
}

// --await-operator: the gateway only watches; the operator's acknowledgement clears the
// stop, and the run's next episode drives again.
TEST_F(GatewayEndToEnd, AfterAnEmergencyStopTheRunWaitsForTheOperatorAndGoesOn) {
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(5000));
  const robot::GatewayConfig config = panda_config();
  GatewayEpisodeRunner runner(config, *controller_, *policy_stub_, recorder());
  arm_->stop("reflex: cartesian_reflex", robot::StopKind::kEmergency);
  EXPECT_EQ(runner.run(episode(912), not_interrupted_).end, EpisodeEnd::kStopped);

  // Nobody clears it: the wait ends at its limit, and the stop stands.
  EXPECT_EQ(
      wait_for_operator(*controller_, std::chrono::milliseconds(300), not_interrupted_, recorder()),
      OperatorWait::kTimedOut);
  EXPECT_EQ(count("awaiting_operator"), 1);
  EXPECT_EQ(arm_->state().stop_kind, robot::StopKind::kEmergency);
  {  // Ctrl-C ends the wait.
    const std::atomic<bool> interrupted{true};
    EXPECT_EQ(wait_for_operator(*controller_, std::chrono::seconds(10), interrupted, recorder()),
              OperatorWait::kInterrupted);
  }
  // The operator acknowledges the reason while the gateway waits: the run goes on.
  std::jthread operator_clears([this] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    arm_->resume({"", "reflex: cartesian_reflex", "ops"});
  });
  EXPECT_EQ(wait_for_operator(*controller_, std::chrono::seconds(10), not_interrupted_, recorder()),
            OperatorWait::kCleared);
  EXPECT_EQ(count("operator_cleared"), 1);
  const EpisodeReport after = runner.run(episode(912), not_interrupted_);
  EXPECT_TRUE(after.end == EpisodeEnd::kSuccess || after.end == EpisodeEnd::kStepCap)
      << episode_end_name(after.end) << ": " << after.reason;
  EXPECT_GT(after.steps, 0);
}

// Between episodes nothing renews the lease: one that lapsed while the gateway waited (for
// a restarting inference service, say) is taken again, unless another client took it.
TEST_F(GatewayEndToEnd, ALeaseThatLapsedBetweenEpisodesIsTakenAgainIfNobodyElseTookIt) {
  const robot::GatewayConfig config = panda_config();  // the runner keeps a reference
  controller_->acquire_lease("test-gateway", std::chrono::milliseconds(300));
  GatewayEpisodeRunner runner(config, *controller_, *policy_stub_, recorder());
  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // lapses
  const EpisodeReport resumed = runner.run(episode(910), not_interrupted_);
  EXPECT_NE(resumed.end, EpisodeEnd::kLeaseLost) << resumed.reason;
  EXPECT_EQ(count("lease_reacquired"), 1);

  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // lapses again
  auto other = link_to(controller_server_->port(), not_interrupted_);
  other->acquire_lease("other", std::chrono::milliseconds(5000));
  const EpisodeReport taken = runner.run(episode(911), not_interrupted_);
  EXPECT_EQ(taken.end, EpisodeEnd::kLeaseLost);
  EXPECT_NE(taken.reason.find("\"other\""), std::string::npos) << taken.reason;
  EXPECT_EQ(taken.steps, 0);
}

TEST_F(GatewayEndToEnd, ASecondGatewayIsRefusedTheLease) {
  controller_->acquire_lease("first", std::chrono::milliseconds(5000));
  auto second = link_to(controller_server_->port(), not_interrupted_);
  try {
    second->acquire_lease("second", std::chrono::milliseconds(5000));
    FAIL() << "two gateways hold the arm";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
    EXPECT_NE(std::string(e.what()).find("\"first\""), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pnp::gateway
