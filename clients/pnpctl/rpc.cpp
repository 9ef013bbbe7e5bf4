#include "clients/pnpctl/rpc.h"

#include <algorithm>
#include <cctype>

#include "common/error.h"
#include "services/common/address.h"
#include "services/common/convert.h"
#include "services/common/status.h"

namespace pnp::pnpctl {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// "approach" <-> ROLE_APPROACH through the enum's generated descriptor, so a new enum
// value needs no change here.
template <typename Enum>
Enum parse_enum(const google::protobuf::EnumDescriptor* descriptor, std::string_view prefix,
                const std::string& name, std::string_view field) {
  std::string full(prefix);
  for (char c : name) full += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  const auto* value = descriptor->FindValueByName(full);
  if (!value || value->number() == 0) {
    std::string expected = "one of";
    for (int i = 1; i < descriptor->value_count(); ++i)
      expected += (i > 1 ? ", " : " ") + lower(descriptor->value(i)->name().substr(prefix.size()));
    throw_invalid_argument(field, expected, "\"" + name + "\"");
  }
  return static_cast<Enum>(value->number());
}

std::string enum_short_name(const google::protobuf::EnumDescriptor* descriptor,
                            std::string_view prefix, int number) {
  const auto* value = descriptor->FindValueByNumber(number);
  if (!value) return std::to_string(number);
  return lower(value->name().substr(prefix.size()));
}

}  // namespace

std::unique_ptr<grpc::ClientContext> context_with_deadline(std::chrono::milliseconds timeout) {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + timeout);
  return context;
}

void check(const grpc::Status& status, std::string_view what, const std::string& address) {
  services::throw_if_error(status, what, address);
}

common::v1::Role parse_role(const std::string& name, std::string_view field) {
  return parse_enum<common::v1::Role>(common::v1::Role_descriptor(), "ROLE_", name, field);
}
train::v1::Algorithm parse_algorithm(const std::string& name, std::string_view field) {
  return parse_enum<train::v1::Algorithm>(train::v1::Algorithm_descriptor(), "ALGORITHM_", name,
                                          field);
}
common::v1::Robot parse_robot(const std::string& name, std::string_view field) {
  return parse_enum<common::v1::Robot>(common::v1::Robot_descriptor(), "ROBOT_", name, field);
}
common::v1::ObjectShape parse_object(const std::string& name, std::string_view field) {
  return parse_enum<common::v1::ObjectShape>(common::v1::ObjectShape_descriptor(), "OBJECT_SHAPE_",
                                             name, field);
}
common::v1::World parse_world(const std::string& name, std::string_view field) {
  return parse_enum<common::v1::World>(common::v1::World_descriptor(), "WORLD_", name, field);
}
sim::Actuation resolve_actuation(const std::string& name, const std::string& robot,
                                 std::string_view field) {
  const sim::Robot arm = services::from_proto(parse_robot(robot, "--robot"), "--robot");
  if (name != "default" && name != "mocap" && name != "arm") {
    throw_invalid_argument(field, "one of default, mocap, arm", "\"" + name + "\"");
  }
  const sim::Actuation actuation =
      name == "default" ? sim::default_actuation(arm) : sim::parse_actuation(name, field);
  sim::require_supported(arm, actuation, field);
  return actuation;
}
common::v1::Actuation parse_actuation(const std::string& name, const std::string& robot,
                                      std::string_view field) {
  return services::to_proto(resolve_actuation(name, robot, field));
}
train::v1::RunState parse_state(const std::string& name, std::string_view field) {
  return parse_enum<train::v1::RunState>(train::v1::RunState_descriptor(), "RUN_STATE_", name,
                                         field);
}

std::string short_name(common::v1::Role role) {
  return enum_short_name(common::v1::Role_descriptor(), "ROLE_", role);
}
std::string short_name(train::v1::Algorithm algorithm) {
  return enum_short_name(train::v1::Algorithm_descriptor(), "ALGORITHM_", algorithm);
}
std::string short_name(train::v1::RunState state) {
  return enum_short_name(train::v1::RunState_descriptor(), "RUN_STATE_", state);
}
std::string short_name(common::v1::Subtask subtask) {
  return enum_short_name(common::v1::Subtask_descriptor(), "SUBTASK_", subtask);
}

}  // namespace pnp::pnpctl
