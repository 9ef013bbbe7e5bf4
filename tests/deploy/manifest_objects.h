#pragma once
// The deployment files as objects for the tests to check: Kubernetes overlays rendered by
// `kubectl kustomize` (the same renderer users apply with), plain YAML files parsed as
// they are, and the small queries the invariants need (which Pods a selector picks, what
// a container's flags say, whether a NetworkPolicy lets one Pod reach another's port).

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace pnp::deploy_test {

using Labels = std::map<std::string, std::string>;

struct Rendered {
  int exit_code = -1;
  std::string errors;  // kubectl's stderr
  std::vector<YAML::Node> objects;
};

// `kubectl kustomize DIR` (PNP_KUBECTL).
Rendered kustomize(const std::filesystem::path& dir);
// Every document of a YAML file.
std::vector<YAML::Node> load_all(const std::filesystem::path& file);

// A Deployment, StatefulSet or Job: what its Pods look like.
struct Workload {
  std::string kind, name;
  int replicas = 1;  // spec.replicas, 1 when absent
  bool has_replicas = false;
  Labels pod_labels;
  YAML::Node pod_spec;
  YAML::Node object;
};
std::vector<Workload> workloads(const std::vector<YAML::Node>& objects);
std::vector<YAML::Node> of_kind(const std::vector<YAML::Node>& objects, const std::string& kind);

Labels labels_of(const YAML::Node& map);
bool selects(const Labels& selector, const Labels& labels);  // an empty selector picks nothing

// A container's command and args as one list, and the value of `--flag=value` (or
// `--flag value`) in it.
std::vector<std::string> command_line(const YAML::Node& container);
std::optional<std::string> flag(const std::vector<std::string>& line, const std::string& name);
// The flags by which one server or client names another tier (the servers' --store and
// --sim-address, pnpctl's --sim ... --inference, the gateway's --controller), and the
// (flag, target) pairs of a command line.
const std::vector<std::string>& client_flags();
std::vector<std::pair<std::string, std::string>> client_targets(
    const std::vector<std::string>& line);
std::vector<int> container_ports(const YAML::Node& container);
// A map with its YAML merge key (`<<: *anchor`) applied: yaml-cpp leaves it as a key.
YAML::Node with_merge_keys(const YAML::Node& map);
int port_of(const std::string& address);  // the number after the last ':'; -1 if none
// "dns:///name:port" or "name:port" -> name (the Service a client flag points at).
std::string host_of(const std::string& target);

// Kubernetes quantities: "500m" / "2" CPU in millicores, "256Mi" / "1Gi" memory in MiB.
long long millicores(const std::string& cpu);
long long mebibytes(const std::string& memory);

// The port a probe or healthcheck command checks, when it is pnpctl checking service
// `name` on loopback (`--NAME=127.0.0.1:PORT ... --only=NAME`); nullopt otherwise.
std::optional<int> probed_port(const std::vector<std::string>& command, const std::string& name);

// The server names scripts/make-dev-certs puts in the server certificate by default, and
// whether one of them (exactly, or a one-label wildcard) covers `host`.
std::vector<std::string> dev_certificate_names(const std::filesystem::path& script);
bool certificate_covers(const std::vector<std::string>& names, const std::string& host);

// Every scalar of a node at any depth, map keys included.
std::vector<std::string> scalars(const YAML::Node& node);
// The files of one kind that some text names ("/run/secrets/inference.key",
// "../dev-certs/bundles/ops/ops.key", "--tls-key=x.key"): for extension "key", the stems
// {"inference", "ops", "x"}.
std::set<std::string> files_named(const std::vector<std::string>& texts,
                                  const std::string& extension);

// A shell command's stdout and exit code (its stderr goes where the test's goes).
struct CommandOutput {
  int exit_code = -1;
  std::string out;
};
CommandOutput run_command(const std::string& command);

// The deployment's identities (scripts/make-dev-certs; docs/RELIABILITY.md, "What each
// identity may do"): the one each compose service and each Kubernetes workload holds, and
// the classes the policy gives each. A service or workload missing here fails the tests
// that ask, so a new one is given an identity on purpose.
const std::map<std::string, std::string>& compose_identities();
const std::map<std::string, std::string>& workload_identities();
const std::map<std::string, std::set<std::string>>& identity_classes();
// The client principals, which also have a token; every other identity is a server's.
const std::set<std::string>& client_principals();

// Whether the NetworkPolicies let a Pod labelled `client` (in the namespace) open a TCP
// connection to `port` of a Pod labelled `server` (ingress rules, matchLabels selectors;
// anything else throws std::invalid_argument rather than guess).
bool may_connect(const std::vector<YAML::Node>& policies, const Labels& client,
                 const Labels& server, int port);

}  // namespace pnp::deploy_test
