#include "clients/pnpctl/endpoints.h"

#include "common/error.h"
#include "services/common/address.h"
#include "services/common/endpoints_file.h"
#include "services/common/replica_channel.h"
#include "services/common/security_flags.h"

namespace pnp::pnpctl {

const std::string& Endpoints::training(const std::string& role) const {
  if (role == "approach") return approach;
  if (role == "manipulate") return manipulate;
  if (role == "retract") return retract;
  if (role == "hlc") return hlc;
  if (role == "e2e") return e2e;
  throw_invalid_argument("--role", "one of approach, manipulate, retract, hlc, e2e",
                         "\"" + role + "\"");
}

const std::string& Endpoints::address_of(const std::string& service) const {
  if (service == "sim") return sim;
  if (service == "inference") return inference;
  if (service == "robot") return robot_controller;
  if (service == "store") return store;
  if (service == "approach" || service == "manipulate" || service == "retract" ||
      service == "hlc" || service == "e2e")
    return training(service);
  throw_invalid_argument("--only",
                         "services among sim, approach, manipulate, retract, hlc, e2e, inference, "
                         "store, robot",
                         "\"" + service + "\"");
}

std::string_view Endpoints::flag_of(const std::string& address) const {
  const std::pair<const std::string*, std::string_view> flags[] = {
      {&sim, "--sim"},
      {&approach, "--approach"},
      {&manipulate, "--manipulate"},
      {&retract, "--retract"},
      {&hlc, "--hlc"},
      {&e2e, "--e2e"},
      {&inference, "--inference"},
      {&robot_controller, "--robot-controller"},
      {&store, "--store"}};
  for (const auto& [field, flag] : flags)
    if (*field == address) return flag;
  return "address";
}

std::shared_ptr<grpc::Channel> Endpoints::channel(const std::string& address) const {
  services::validate_address(address, flag_of(address));  // the flag the user typed
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(64 << 20);
  // Inference replicas are interchangeable: balanced, idempotent calls retried.
  if (address == inference) services::balance_over_replicas(args);
  return services::dial(address, tls, args);
}

void add_endpoint_options(CLI::App& app, Endpoints& e) {
  // Each address also comes from the environment (PNP_SIM_ADDRESS, ...): a shell that
  // talks to one deployment sets them once; a flag still wins.
  auto add = [&app](const char* flag, std::string& address, const char* env, const char* what) {
    app.add_option(flag, address, what)->envname(env)->capture_default_str();
  };
  add("--sim", e.sim, "PNP_SIM_ADDRESS", "simulation service address");
  add("--approach", e.approach, "PNP_APPROACH_ADDRESS", "approach training service");
  add("--manipulate", e.manipulate, "PNP_MANIPULATE_ADDRESS", "manipulate training service");
  add("--retract", e.retract, "PNP_RETRACT_ADDRESS", "retract training service");
  add("--hlc", e.hlc, "PNP_HLC_ADDRESS", "choreographer training service");
  add("--e2e", e.e2e, "PNP_E2E_ADDRESS", "end-to-end training service");
  add("--inference", e.inference, "PNP_INFERENCE_ADDRESS", "inference service address");
  add("--robot-controller", e.robot_controller, "PNP_ROBOT_CONTROLLER_ADDRESS",
      "robot controller address (pnp-robot-sim); health --only robot");
  add("--store", e.store, "PNP_STORE_ADDRESS", "pnp-store-server address; health --only store");
  services::add_endpoints_file_option(app, e.endpoints_file);
  services::add_client_security_flags(app, e.tls);
}

void apply_endpoints_file(const CLI::App& app, Endpoints& e) {
  const services::FileAddress addresses[] = {
      {"sim", "--sim", &e.sim},
      {"approach", "--approach", &e.approach},
      {"manipulate", "--manipulate", &e.manipulate},
      {"retract", "--retract", &e.retract},
      {"hlc", "--hlc", &e.hlc},
      {"e2e", "--e2e", &e.e2e},
      {"inference", "--inference", &e.inference},
      {"robot_controller", "--robot-controller", &e.robot_controller},
      {"store", "--store", &e.store},
  };
  e.endpoints_file = services::apply_endpoints_file(app, e.endpoints_file, addresses);
}

std::string with_endpoints_hint(const Endpoints& e, const std::string& message) {
  return services::with_endpoints_file_hint(e.endpoints_file, message);
}

}  // namespace pnp::pnpctl
