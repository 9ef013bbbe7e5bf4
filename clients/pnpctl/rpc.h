#pragma once
// Talking to the services: deadlines, failed calls as one clear error, and the
// proto enums as the short names users type ("approach", "ddpg_her", "fetch").

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <string>
#include <string_view>

#include "pnp/common/v1/common.pb.h"
#include "pnp/train/v1/train_service.pb.h"
#include "sim/actuation.h"

namespace pnp::pnpctl {

// A context whose call gives up after `timeout` (unary calls never hang on a dead server).
std::unique_ptr<grpc::ClientContext> context_with_deadline(
    std::chrono::milliseconds timeout = std::chrono::seconds(30));

// Throws pnp::Error (UNAVAILABLE for a service that cannot be reached, otherwise the
// status's code) with "<what> (<address>): <CODE>: <message>".
void check(const grpc::Status& status, std::string_view what, const std::string& address);

common::v1::Role parse_role(const std::string& name, std::string_view field);
train::v1::Algorithm parse_algorithm(const std::string& name, std::string_view field);
common::v1::Robot parse_robot(const std::string& name, std::string_view field);
common::v1::ObjectShape parse_object(const std::string& name, std::string_view field);
common::v1::World parse_world(const std::string& name, std::string_view field);
// "mocap" or "arm", or "default": the robot's own (sim::default_actuation), resolved here
// so that what is printed names what runs. The robot is a --robot value (checked first);
// an actuation the robot does not have is INVALID_ARGUMENT naming `field`.
sim::Actuation resolve_actuation(const std::string& name, const std::string& robot,
                                 std::string_view field);
common::v1::Actuation parse_actuation(const std::string& name, const std::string& robot,
                                      std::string_view field);
train::v1::RunState parse_state(const std::string& name, std::string_view field);

// "approach" for ROLE_APPROACH, "running" for RUN_STATE_RUNNING...
std::string short_name(common::v1::Role role);
std::string short_name(train::v1::Algorithm algorithm);
std::string short_name(train::v1::RunState state);
std::string short_name(common::v1::Subtask subtask);

}  // namespace pnp::pnpctl
