#include "robot/arm_controller.h"

#include <cmath>

#include "common/error.h"
#include "robot/controller_intake.h"

namespace pnp::robot {
namespace {

LeaseBook::Clock::duration seconds(double s) {
  return std::chrono::duration_cast<LeaseBook::Clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

std::string_view stop_kind_name(StopKind kind) {
  switch (kind) {
    case StopKind::kNone:
      return "none";
    case StopKind::kProtective:
      return "protective";
    case StopKind::kEmergency:
      return "emergency";
  }
  return "unknown";
}

ArmController::CallerLock::CallerLock(const ArmController& controller) : controller_(controller) {
  controller_.callers_waiting_.fetch_add(1, std::memory_order_acq_rel);
  controller_.mutex_.lock();
  controller_.callers_waiting_.fetch_sub(1, std::memory_order_acq_rel);
}

ArmController::CallerLock::~CallerLock() {
  controller_.mutex_.unlock();
}

ArmController::ArmController(ArmBackend& arm, ArmControllerOptions options)
    : options_(std::move(options)), arm_(arm) {
  options_.limits.validate();
  if (options_.base_frame_id.empty()) {
    throw_invalid_argument("base_frame_id", "a frame name", "\"\"");
  }
  if (!(options_.default_lease_timeout_s > 0) ||
      !(options_.max_lease_timeout_s >= options_.default_lease_timeout_s)) {
    throw_invalid_argument("default_lease_timeout_s", "a positive time at most the maximum",
                           std::to_string(options_.default_lease_timeout_s));
  }
  std::lock_guard lock(mutex_);
  publish_locked();
}

ArmController::Lease ArmController::acquire_lease(const std::string& client, double timeout_s) {
  const double t = timeout_s == 0 ? options_.default_lease_timeout_s : timeout_s;
  if (!(t > 0) || t > options_.max_lease_timeout_s) {
    throw_invalid_argument(
        "timeout", "a duration in (0, " + std::to_string(options_.max_lease_timeout_s) + "] s",
        std::to_string(timeout_s) + " s");
  }
  const CallerLock lock(*this);
  Lease lease{leases_.acquire(client, seconds(t), LeaseBook::Clock::now()), t};
  publish_locked();
  return lease;
}

void ArmController::release_lease(const std::string& lease_id) {
  const CallerLock lock(*this);
  leases_.release(lease_id);
  publish_locked();
}

void ArmController::require_lease(const std::string& lease_id,
                                  LeaseBook::Clock::time_point now) const {
  if (!leases_.valid(lease_id, now)) {
    const auto holder = leases_.holder(now);
    throw Error(ErrorCode::kFailedPrecondition,
                "lease_id: not the current lease" +
                    (holder ? " (the arm is leased to \"" + *holder + "\")"
                            : std::string(" (nobody holds one: acquire a lease)")));
  }
}

void ArmController::require_not_stopped(std::string_view action) const {
  if (arm_.reading().mode == ArmMode::kStopped) {
    throw_failed_precondition("the arm is stopped (" + std::string(stop_kind_name(stop_kind_)) +
                              " stop: " + stop_reason_ + "): clear it before " +
                              std::string(action));
  }
}

std::uint64_t ArmController::open_stream(const std::string& lease_id) {
  const CallerLock lock(*this);
  const auto now = LeaseBook::Clock::now();
  require_lease(lease_id, now);
  leases_.renew(lease_id, now);
  last_sequence_ = 0;
  ++current_stream_;
  publish_locked();
  return current_stream_;
}

std::optional<std::string> ArmController::target_error(const TargetRequest& target) const {
  if (target.frame_id != options_.base_frame_id) {
    return "frame_id: expected \"" + options_.base_frame_id + "\", got \"" + target.frame_id + "\"";
  }
  if (target.sequence <= last_sequence_) {
    return "sequence: expected more than " + std::to_string(last_sequence_) + ", got " +
           std::to_string(target.sequence);
  }
  if (!std::isfinite(target.max_speed_m_per_s) || target.max_speed_m_per_s < 0) {
    return "max_speed_m_per_s: expected a non-negative speed (0: default), got " +
           std::to_string(target.max_speed_m_per_s);
  }
  return std::nullopt;
}

std::optional<std::string> ArmController::stale_error(const TargetRequest& target) const {
  const double limit = options_.limits.max_target_age_s;
  if (!target.stamp) return "stamp: missing (a target must say when it was computed)";
  // In lockstep the physics waits for each target: none answers a state that has moved on.
  if (options_.lockstep) return std::nullopt;
  const double age_s =
      std::chrono::duration<double>(std::chrono::system_clock::now() - *target.stamp).count();
  if (age_s > limit) {
    return "stamp: the target is " + std::to_string(age_s) + " s old, more than the controller's " +
           "max_target_age_s " + std::to_string(limit) + " s";
  }
  if (age_s < -limit) {
    return "stamp: " + std::to_string(-age_s) + " s in the future (clocks out of step by more " +
           "than max_target_age_s " + std::to_string(limit) + " s)";
  }
  return std::nullopt;
}

ControllerReport ArmController::take_target(const std::string& lease_id, std::uint64_t stream_id,
                                            const TargetRequest& target) {
  const CallerLock lock(*this);
  ControllerStatus status = ControllerStatus::kOk;
  std::vector<std::string> errors;
  const auto refuse = [&](ControllerStatus s, std::string why) {
    status = s;
    errors.push_back(std::move(why));
  };
  if (stream_id != current_stream_) {
    refuse(ControllerStatus::kLeaseLost,
           "stream: superseded by a newer stream on this lease; the arm holds");
  } else if (!leases_.renew(lease_id, LeaseBook::Clock::now())) {
    refuse(ControllerStatus::kLeaseLost,
           "lease_id: the lease expired or was taken over; the arm holds");
  } else if (arm_.reading().mode == ArmMode::kStopped) {
    refuse(ControllerStatus::kStopped,
           std::string(stop_kind_name(stop_kind_)) + " stop: " + stop_reason_);
  } else if (const BackendReading arm = arm_.reading(); arm.mode == ArmMode::kFault) {
    refuse(ControllerStatus::kStopped, "the arm faulted: " + arm.fault);
  } else if (auto error = target_error(target)) {
    refuse(ControllerStatus::kInvalidTarget, std::move(*error));
  } else if (auto stale = stale_error(target)) {
    refuse(ControllerStatus::kStale, std::move(*stale));
  } else {
    IntakeOutcome taken = take_into_arm(
        arm_, options_.limits,
        {target.position_m, target.orientation, target.gripper_width_m, target.max_speed_m_per_s});
    status = taken.status;
    if (taken.accepted()) {
      last_sequence_ = target.sequence;
    } else {
      errors.push_back(std::move(taken.error));
    }
  }
  arm_.after_target();
  publish_locked();
  return report_locked(status, std::move(errors));
}

ControllerReport ArmController::report_locked(ControllerStatus status,
                                              std::vector<std::string> errors) const {
  ControllerReport report;
  report.arm = arm_.reading();
  report.sequence = last_sequence_;
  report.status = status;
  report.errors = std::move(errors);
  report.stop_kind = stop_kind_;
  report.stop_reason = stop_reason_;
  if (status == ControllerStatus::kOk && report.arm.mode == ArmMode::kStopped) {
    report.status = ControllerStatus::kStopped;
    report.errors.push_back(std::string(stop_kind_name(stop_kind_)) + " stop: " + stop_reason_);
  }
  return report;
}

void ArmController::publish_locked() {
  // An arm that stopped itself (a reflex, a stalled state topic) is under an emergency
  // stop from here on: its reason is what an operator acknowledges to clear it.
  if (stop_kind_ == StopKind::kNone) {
    const BackendReading arm = arm_.reading();
    if (arm.mode == ArmMode::kStopped && !arm.fault.empty()) {
      stop_kind_ = StopKind::kEmergency;
      stop_reason_ = arm.fault;
    }
  }
  ControllerReport report = report_locked(ControllerStatus::kOk, {});
  std::lock_guard lock(published_mutex_);
  published_ = std::move(report);
  published_leases_ = leases_;
}

ControllerReport ArmController::state() const {
  std::lock_guard lock(published_mutex_);
  return published_;
}

std::optional<std::string> ArmController::lease_holder() const {
  std::lock_guard lock(published_mutex_);
  return published_leases_.holder(LeaseBook::Clock::now());
}

ControllerReport ArmController::stop(const std::string& reason, StopKind kind) {
  if (kind == StopKind::kNone) throw_invalid_argument("kind", "protective or emergency", "none");
  const CallerLock lock(*this);
  arm_.stop();
  if (arm_.reading().mode == ArmMode::kStopped && kind > stop_kind_) {
    stop_kind_ = kind;
    stop_reason_ = reason.empty() ? "no reason given" : reason;
  }
  publish_locked();
  return report_locked(ControllerStatus::kOk, {});
}

ArmController::Cleared ArmController::resume(const ResumeRequest& request) {
  const CallerLock lock(*this);
  if (arm_.reading().mode != ArmMode::kStopped) {
    throw_failed_precondition("the arm is not stopped: nothing to clear");
  }
  if (stop_kind_ == StopKind::kEmergency) {
    if (request.operator_name.empty()) {
      throw_invalid_argument("operator_name", "who clears the emergency stop (an operator action)",
                             "\"\"");
    }
    if (request.acknowledged_reason != stop_reason_) {
      throw Error(ErrorCode::kFailedPrecondition,
                  "acknowledged_reason: an emergency stop is cleared by acknowledging its reason "
                  "\"" +
                      stop_reason_ + "\", got \"" + request.acknowledged_reason + "\"");
    }
  } else {
    require_lease(request.lease_id, LeaseBook::Clock::now());
  }
  Cleared cleared{stop_kind_, stop_reason_};
  arm_.resume();
  stop_kind_ = StopKind::kNone;
  stop_reason_.clear();
  publish_locked();
  return cleared;
}

}  // namespace pnp::robot
