#pragma once
// A controller's network side: the rules a real arm's controller enforces whatever drives
// it, over any arm (robot::ArmBackend: the simulated Panda of pnp-robot-sim, a Franka
// behind pnp-franka-bridge). One lease holder drives the arm, over one stream at a time
// (a new stream supersedes the old one); targets must name the base frame, carry
// increasing sequence numbers, be fresh (their stamp) and stay within the controller's own
// limits (controller_limits.h). Anyone may stop the arm, at once: an emergency stop lasts
// until an operator clears it acknowledging its reason; a protective stop (what a client
// sends when it loses track of the arm) may be cleared by the lease holder, as libfranka's
// automatic error recovery clears a reflex. An arm that stops itself (a real arm's reflex,
// BackendReading::fault) is under an emergency stop with that reason.
//
// Thread-safe: every call takes the controller's lock; state() reads the snapshot
// published after each change, so it never waits for the arm. A backend with a clock of
// its own (the stand-in's 1 kHz loop) changes the arm through run_tick().

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "robot/arm_backend.h"
#include "robot/controller_limits.h"
#include "robot/lease_book.h"

namespace pnp::robot {

struct ArmControllerOptions {
  std::string base_frame_id = "panda_link0";
  double default_lease_timeout_s = 0.5;  // when a client asks for none (the proto's default)
  double max_lease_timeout_s = 60.0;
  ControllerLimits limits;  // the controller's own: never from the network
  // The arm advances only when a target is taken in (a lockstep simulation): no target
  // answers a state that has moved on, so freshness is not checked.
  bool lockstep = false;
  double tcp_from_flange_m = 0;  // the point every pose names (GetState reports it)
};

enum class StopKind { kNone, kProtective, kEmergency };
std::string_view stop_kind_name(StopKind kind);  // "none", "protective", "emergency"

struct ControllerReport {
  BackendReading arm;
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

class ArmController {
 public:
  // `arm` must outlive the controller. INVALID_ARGUMENT for options out of range.
  ArmController(ArmBackend& arm, ArmControllerOptions options);
  virtual ~ArmController() = default;
  ArmController(const ArmController&) = delete;
  ArmController& operator=(const ArmController&) = delete;

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
  // status (never an exception for bad target values). The backend's after_target() runs
  // either way.
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

  const std::string& base_frame_id() const { return options_.base_frame_id; }
  double tcp_from_flange_m() const { return options_.tcp_from_flange_m; }
  bool lockstep() const { return options_.lockstep; }
  const ControllerLimits& limits() const { return options_.limits; }

 protected:
  // The caller's hold on the controller; a backend's own clock lets waiting calls in
  // before each tick (std::mutex is not fair).
  class CallerLock {
   public:
    explicit CallerLock(const ArmController& controller);
    ~CallerLock();
    CallerLock(const CallerLock&) = delete;
    CallerLock& operator=(const CallerLock&) = delete;

   private:
    const ArmController& controller_;
  };
  // One tick of the arm's own clock: after any waiting call, `tick()` under the lock,
  // then the state is published.
  template <typename Tick>
  void run_tick(Tick&& tick) {
    while (callers_waiting_.load(std::memory_order_acquire) > 0) std::this_thread::yield();
    std::lock_guard lock(mutex_);
    tick();
    publish_locked();
  }
  // With a CallerLock held.
  void require_lease(const std::string& lease_id, LeaseBook::Clock::time_point now) const;
  void require_not_stopped(std::string_view action) const;
  ControllerReport report_locked(ControllerStatus status, std::vector<std::string> errors) const;
  void publish_locked();  // after every change: what state() returns

 private:
  std::optional<std::string> target_error(const TargetRequest& target) const;
  std::optional<std::string> stale_error(const TargetRequest& target) const;

  const ArmControllerOptions options_;
  ArmBackend& arm_;
  mutable std::mutex mutex_;
  mutable std::atomic<int> callers_waiting_{0};
  LeaseBook leases_;                      // guarded by mutex_
  std::uint64_t last_sequence_ = 0;       // guarded by mutex_
  std::uint64_t current_stream_ = 0;      // guarded by mutex_; 0: none yet
  StopKind stop_kind_ = StopKind::kNone;  // guarded by mutex_
  std::string stop_reason_;               // guarded by mutex_
  // The latest state, readable without waiting for the arm.
  mutable std::mutex published_mutex_;
  ControllerReport published_;  // guarded by published_mutex_
  LeaseBook published_leases_;  // guarded by published_mutex_
};

}  // namespace pnp::robot
