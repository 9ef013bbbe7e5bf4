#include "clients/pnpctl/endpoints.h"

#include "common/error.h"

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
  if (service == "approach" || service == "manipulate" || service == "retract" ||
      service == "hlc" || service == "e2e")
    return training(service);
  throw_invalid_argument("--only",
                         "services among sim, approach, manipulate, retract, hlc, e2e, inference, "
                         "robot",
                         "\"" + service + "\"");
}

void add_endpoint_options(CLI::App& app, Endpoints& e) {
  app.add_option("--sim", e.sim, "simulation service address")->capture_default_str();
  app.add_option("--approach", e.approach, "approach training service")->capture_default_str();
  app.add_option("--manipulate", e.manipulate, "manipulate training service")
      ->capture_default_str();
  app.add_option("--retract", e.retract, "retract training service")->capture_default_str();
  app.add_option("--hlc", e.hlc, "choreographer training service")->capture_default_str();
  app.add_option("--e2e", e.e2e, "end-to-end training service")->capture_default_str();
  app.add_option("--inference", e.inference, "inference service address")->capture_default_str();
  app.add_option("--robot-controller", e.robot_controller,
                 "robot controller address (pnp-robot-sim); health --only robot")
      ->capture_default_str();
}

}  // namespace pnp::pnpctl
