#include "clients/pnpctl/endpoints.h"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "common/error.h"
#include "services/common/address.h"
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
  app.add_option("--endpoints", e.endpoints_file,
                 std::string("JSON file of service addresses, for those no flag or variable "
                             "gives (scripts/run writes ") +
                     kDefaultEndpointsFile + ", read when it exists)")
      ->envname("PNP_ENDPOINTS");
  services::add_client_security_flags(app, e.tls);
}

namespace {

// The file's keys: the services' names, as scripts/run and the Python package write them.
struct FileKey {
  const char* key;
  const char* flag;
  std::string Endpoints::*field;
};
constexpr FileKey kFileKeys[] = {
    {"sim", "--sim", &Endpoints::sim},
    {"approach", "--approach", &Endpoints::approach},
    {"manipulate", "--manipulate", &Endpoints::manipulate},
    {"retract", "--retract", &Endpoints::retract},
    {"hlc", "--hlc", &Endpoints::hlc},
    {"e2e", "--e2e", &Endpoints::e2e},
    {"inference", "--inference", &Endpoints::inference},
    {"robot_controller", "--robot-controller", &Endpoints::robot_controller},
    {"store", "--store", &Endpoints::store},
};
constexpr std::uintmax_t kMaxEndpointsFileBytes = 64 * 1024;

nlohmann::json read_endpoints_file(const std::string& path) {
  std::error_code error;
  const auto size = std::filesystem::file_size(path, error);
  if (error) throw Error(ErrorCode::kNotFound, "--endpoints: cannot read " + path);
  if (size > kMaxEndpointsFileBytes) {
    throw_invalid_argument("--endpoints", "a file of at most 64 KiB",
                           path + " of " + std::to_string(size) + " bytes");
  }
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json doc = nlohmann::json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
  if (!doc.is_object())
    throw_invalid_argument("--endpoints", "a JSON object of service addresses", path);
  return doc;
}

const FileKey& file_key(const std::string& path, const std::string& key) {
  for (const FileKey& k : kFileKeys)
    if (key == k.key) return k;
  throw_invalid_argument(path + ": " + key,
                         "one of sim, approach, manipulate, retract, hlc, e2e, inference, "
                         "robot_controller, store",
                         "an unknown key");
}

}  // namespace

void apply_endpoints_file(const CLI::App& app, Endpoints& e) {
  std::string path = e.endpoints_file;
  if (path.empty()) {
    if (!std::filesystem::exists(kDefaultEndpointsFile)) return;
    path = kDefaultEndpointsFile;
  }
  const nlohmann::json doc = read_endpoints_file(path);
  for (const auto& [key, value] : doc.items()) {
    const FileKey& known = file_key(path, key);
    if (!value.is_string() || value.get<std::string>().empty())
      throw_invalid_argument(path + ": " + key, "a host:port string", value.dump());
    if (app.get_option(known.flag)->count() == 0) e.*(known.field) = value.get<std::string>();
  }
  e.endpoints_file = path;
}

std::string with_endpoints_hint(const Endpoints& e, const std::string& message) {
  if (e.endpoints_file.empty()) return message;
  return message + "\n(the addresses came from " + e.endpoints_file +
         ": if the platform that wrote it has stopped, start it again with scripts/run, or "
         "give the addresses with flags or PNP_*_ADDRESS)";
}

}  // namespace pnp::pnpctl
