#pragma once
// What pnp-robot-sim serves: a SimulatedArm behind the rules a real arm's controller
// enforces for its network side. One lease holder drives it, over one stream at a time (a
// new stream supersedes the old one); targets must name the base frame, carry increasing
// sequence numbers, be fresh (their stamp) and stay within the controller's own limits
// (controller_limits.h). Anyone may stop the arm, at once: an emergency stop lasts until
// an operator clears it acknowledging its reason; a protective stop (what a client sends
// when it loses track of the arm) may be cleared by the lease holder, as libfranka's
// automatic error recovery clears a reflex. Thread-safe: every change takes the
// arm's lock for the call (the control loop for one tick); state() reads the snapshot
// published after each change, so it never waits for the loop.
//
// Two clocks. Real time: a thread runs the 1 kHz control loop against the steady clock,
// as the arm would, whatever the network does. Lockstep: the physics advances one policy
// period for each target taken in, and not otherwise, so a gateway can run episodes as
// fast as the computer allows (evaluations, tests) with the same physics.

#include <Eigen/Core>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "arm_sim/controller_intake.h"
#include "arm_sim/controller_limits.h"
#include "arm_sim/simulated_arm.h"
#include "robot/lease_book.h"

namespace pnp::arm_sim {

enum class ClockMode { kRealTime, kLockstep };

struct StandInOptions {
  sim::ObjectShape object = sim::ObjectShape::kBlock;
  sim::WorldProfile world = sim::kDefaultWorldProfile;  // the simulation's world profile
  ClockMode clock = ClockMode::kRealTime;
  std::string base_frame_id = "panda_link0";
  double default_lease_timeout_s = 0.5;  // when a client asks for none (the proto's default)
  double max_lease_timeout_s = 60.0;
  ControllerLimits limits;  // the controller's own: never from the network
  ArmControllerOptions arm;
};

enum class StopKind { kNone, kProtective, kEmergency };
std::string_view stop_kind_name(StopKind kind);  // "none", "protective", "emergency"

struct ControllerReport {
  ArmState arm;
  std::uint64_t sequence = 0;  // the last target taken in on the lease's stream
  ControllerStatus status = ControllerStatus::kOk;
  std::vector<std::string> errors;  // why, for any status but kOk
  StopKind stop_kind = StopKind::kNone;
  std::string stop_reason;  // while stopped
};

struct TargetRequest {
  std::uint64_t sequence = 0;
  std::string frame_id;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  double gripper_width_m = 0;
  double max_speed_m_per_s = 0;
  // When the client computed it; a target without one is stale.
  std::optional<std::chrono::system_clock::time_point> stamp;
};

struct ResumeRequest {
  std::string lease_id;             // a protective stop: the lease holder clears it
  std::string acknowledged_reason;  // an emergency stop: its reason, as GetState reports it
  std::string operator_name;        // an emergency stop: who clears it (logged)
};

class ControllerStandIn {
 public:
  explicit ControllerStandIn(const StandInOptions& options);
  ~ControllerStandIn();
  ControllerStandIn(const ControllerStandIn&) = delete;
  ControllerStandIn& operator=(const ControllerStandIn&) = delete;

  struct Lease {
    std::string id;
    double timeout_s = 0;
  };
  // timeout_s 0: the default. INVALID_ARGUMENT for a timeout outside (0, max];
  // FAILED_PRECONDITION naming the holder while someone else holds the lease.
  Lease acquire_lease(const std::string& client, double timeout_s);
  void release_lease(const std::string& lease_id);  // NOT_FOUND for an unknown lease

  // A drive stream opens: FAILED_PRECONDITION unless `lease_id` is the current lease. It
  // supersedes any earlier stream (whose targets are refused from now on) and its
  // sequence numbering starts again. Returns the stream's id.
  std::uint64_t open_stream(const std::string& lease_id);
  // One target of stream `stream_id`, opened with `lease_id`: taken in, or refused with a
  // status (never an exception for bad target values). In lockstep the physics then
  // advances one policy period, refused or not: time passes for a real arm too.
  ControllerReport take_target(const std::string& lease_id, std::uint64_t stream_id,
                               const TargetRequest& target);

  ControllerReport state() const;
  std::optional<std::string> lease_holder() const;

  // Anyone may. A stop never weakens one in force (a protective stop during an emergency
  // stop stays an emergency stop) and keeps the first reason of its kind.
  ControllerReport stop(const std::string& reason, StopKind kind);
  // Clears a stop: an emergency stop needs an operator's name and its reason acknowledged
  // word for word, a protective one the lease. FAILED_PRECONDITION (naming what is
  // missing) otherwise, or when the arm is not stopped. Returns the stop it cleared.
  struct Cleared {
    StopKind kind = StopKind::kNone;
    std::string reason;
  };
  Cleared resume(const ResumeRequest& request);
  struct SceneReset {
    ControllerReport report;
    Eigen::Vector3d goal_base;
  };
  SceneReset reset_scene(const std::string& lease_id, std::uint64_t seed);

  const std::string& base_frame_id() const { return options_.base_frame_id; }
  // The grip point every pose names, from the flange (the model's site "grip").
  double tcp_from_flange_m() const;
  ClockMode clock() const { return options_.clock; }

 private:
  void require_lease(const std::string& lease_id, robot::LeaseBook::Clock::time_point now) const;
  ControllerReport report_locked(ControllerStatus status, std::vector<std::string> errors) const;
  void publish_locked();  // after every change: what state() returns

  // A call's hold on the arm: the control loop lets waiting calls in before its next tick.
  class CallerLock {
   public:
    explicit CallerLock(const ControllerStandIn& arm);
    ~CallerLock();
    CallerLock(const CallerLock&) = delete;
    CallerLock& operator=(const CallerLock&) = delete;

   private:
    const ControllerStandIn& arm_;
  };
  std::optional<std::string> target_error(const TargetRequest& target) const;
  std::optional<std::string> stale_error(const TargetRequest& target) const;
  void run_real_time(const std::stop_token& stop);

  const StandInOptions options_;
  mutable std::mutex mutex_;
  mutable std::atomic<int> callers_waiting_{0};
  SimulatedArm arm_;                      // guarded by mutex_
  robot::LeaseBook leases_;               // guarded by mutex_
  std::uint64_t last_sequence_ = 0;       // guarded by mutex_
  std::uint64_t current_stream_ = 0;      // guarded by mutex_; 0: none yet
  StopKind stop_kind_ = StopKind::kNone;  // guarded by mutex_
  std::string stop_reason_;               // guarded by mutex_
  // The latest state, readable without waiting for the control loop's lock.
  mutable std::mutex published_mutex_;
  ControllerReport published_;         // guarded by published_mutex_
  robot::LeaseBook published_leases_;  // guarded by published_mutex_
  std::jthread clock_thread_;          // real time only; last member: stops first
};

}  // namespace pnp::arm_sim
