#include "clients/robot_gateway/operator_wait.h"

#include <thread>

namespace pnp::gateway {
namespace {

namespace rv1 = robot::v1;
using Clock = std::chrono::steady_clock;

}  // namespace

std::string_view operator_wait_name(OperatorWait outcome) {
  switch (outcome) {
    case OperatorWait::kCleared:
      return "cleared";
    case OperatorWait::kTimedOut:
      return "timed_out";
    case OperatorWait::kInterrupted:
      return "interrupted";
  }
  return "unknown";
}

OperatorWait wait_for_operator(ControllerLink& controller, std::chrono::milliseconds limit,
                               const std::atomic<bool>& interrupted, const EventLog& log) {
  const auto give_up = Clock::now() + limit;
  bool announced = false;
  OperatorWait outcome = OperatorWait::kTimedOut;
  while (Clock::now() < give_up) {
    if (interrupted.load()) {
      outcome = OperatorWait::kInterrupted;
      break;
    }
    const auto next = Clock::now() + kOperatorPoll;
    std::optional<rv1::GetStateResponse> state;
    try {
      state = controller.state(kOperatorPoll);
    } catch (const std::exception&) {  // unreachable for now: read again at the next poll
    }
    if (state && state->stop_kind() != rv1::STOP_KIND_EMERGENCY) {
      outcome = OperatorWait::kCleared;
      break;
    }
    if (state && !announced) {
      log("awaiting_operator",
          {{"stop_reason", state->stop_reason()},
           {"limit_s", std::chrono::duration<double>(limit).count()},
           {"clear_with", "pnpctl robot resume --ack '" + state->stop_reason() + "'"}});
      announced = true;
    }
    std::this_thread::sleep_until(std::min(next, give_up));
  }
  log(outcome == OperatorWait::kCleared ? "operator_cleared" : "operator_wait_ended",
      {{"outcome", operator_wait_name(outcome)}});
  return outcome;
}

}  // namespace pnp::gateway
