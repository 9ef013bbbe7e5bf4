#pragma once
// After an emergency stop (a reflex, a stalled arm, anyone's E-stop) a run may wait for an
// operator to clear it and then go on with its next episode. Only the operator clears the
// stop (pnpctl robot resume --ack REASON); the gateway just watches the controller's
// state, drives nothing meanwhile, and gives way to Ctrl-C.

#include <atomic>
#include <chrono>
#include <string_view>

#include "clients/robot_gateway/controller_link.h"
#include "clients/robot_gateway/gateway_episode.h"

namespace pnp::gateway {

enum class OperatorWait { kCleared, kTimedOut, kInterrupted };
std::string_view operator_wait_name(OperatorWait outcome);

// How often the controller's state is read while waiting.
inline constexpr std::chrono::milliseconds kOperatorPoll{100};

// Reads the controller's state every kOperatorPoll until its emergency stop is cleared,
// `limit` has passed or `interrupted` is set. A controller that does not answer (a
// restarting bridge) is read again at the next poll. Logs "awaiting_operator" with the
// stop's reason once, then "operator_cleared" or "operator_wait_ended".
OperatorWait wait_for_operator(ControllerLink& controller, std::chrono::milliseconds limit,
                               const std::atomic<bool>& interrupted, const EventLog& log);

}  // namespace pnp::gateway
