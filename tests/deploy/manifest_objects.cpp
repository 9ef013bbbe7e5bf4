#include "tests/deploy/manifest_objects.h"

#include <array>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace pnp::deploy_test {
namespace {

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<YAML::Node> documents(const std::string& text) {
  std::vector<YAML::Node> out;
  for (const YAML::Node& doc : YAML::LoadAll(text))
    if (doc.IsMap()) out.push_back(doc);
  return out;
}

// matchLabels only: a selector this evaluator cannot judge fails the test that asked.
Labels simple_selector(const YAML::Node& selector) {
  if (selector && selector["matchExpressions"])
    throw std::invalid_argument("a selector with matchExpressions: not evaluated here");
  return selector ? labels_of(selector["matchLabels"]) : Labels{};
}

bool peer_matches(const YAML::Node& peer, const Labels& client) {
  if (peer["ipBlock"]) return true;  // any address: a Pod's too
  const YAML::Node namespaces = peer["namespaceSelector"];
  const YAML::Node pods = peer["podSelector"];
  if (namespaces && !simple_selector(namespaces).empty())
    throw std::invalid_argument("a namespaceSelector with labels: not evaluated here");
  // Every namespace's Pods ({}), or Pods of this namespace matching the pod selector.
  if (namespaces && labels_of(namespaces["matchLabels"]).empty() && !pods) return true;
  if (!pods) return false;
  const Labels wanted = simple_selector(pods);
  return wanted.empty() || selects(wanted, client);
}

bool port_matches(const YAML::Node& rule_port, int port) {
  if (!rule_port["port"]) return true;
  const int first = rule_port["port"].as<int>();
  const int last = rule_port["endPort"] ? rule_port["endPort"].as<int>() : first;
  return port >= first && port <= last;
}

}  // namespace

Rendered kustomize(const std::filesystem::path& dir) {
  const auto errors = std::filesystem::temp_directory_path() /
                      ("kustomize-" + std::to_string(::getpid()) + ".stderr");
  const std::string command = std::string("'") + PNP_KUBECTL + "' kustomize '" + dir.string() +
                              "' 2>'" + errors.string() + "'";
  Rendered out;
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(::popen(command.c_str(), "r"), ::pclose);
  if (!pipe) throw std::runtime_error("cannot run " + command);
  std::string text;
  std::array<char, 4096> buffer{};
  for (std::size_t n; (n = std::fread(buffer.data(), 1, buffer.size(), pipe.get())) > 0;)
    text.append(buffer.data(), n);
  const int status = ::pclose(pipe.release());
  out.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  out.errors = read_file(errors);
  std::filesystem::remove(errors);
  if (out.exit_code == 0) out.objects = documents(text);
  return out;
}

std::vector<YAML::Node> load_all(const std::filesystem::path& file) {
  return documents(read_file(file));
}

std::vector<Workload> workloads(const std::vector<YAML::Node>& objects) {
  std::vector<Workload> out;
  for (const YAML::Node& object : objects) {
    const auto kind = object["kind"].as<std::string>();
    if (kind != "Deployment" && kind != "StatefulSet" && kind != "Job") continue;
    Workload w;
    w.kind = kind;
    w.name = object["metadata"]["name"].as<std::string>();
    if (object["spec"]["replicas"]) {
      w.replicas = object["spec"]["replicas"].as<int>();
      w.has_replicas = true;
    }
    w.pod_labels = labels_of(object["spec"]["template"]["metadata"]["labels"]);
    w.pod_spec = object["spec"]["template"]["spec"];
    w.object = object;
    out.push_back(std::move(w));
  }
  return out;
}

std::vector<YAML::Node> of_kind(const std::vector<YAML::Node>& objects, const std::string& kind) {
  std::vector<YAML::Node> out;
  for (const YAML::Node& object : objects)
    if (object["kind"].as<std::string>() == kind) out.push_back(object);
  return out;
}

Labels labels_of(const YAML::Node& map) {
  Labels out;
  if (!map || !map.IsMap()) return out;
  for (const auto& entry : map) out[entry.first.as<std::string>()] = entry.second.as<std::string>();
  return out;
}

bool selects(const Labels& selector, const Labels& labels) {
  if (selector.empty()) return false;
  for (const auto& [key, value] : selector) {
    const auto found = labels.find(key);
    if (found == labels.end() || found->second != value) return false;
  }
  return true;
}

std::vector<std::string> command_line(const YAML::Node& container) {
  std::vector<std::string> out;
  for (const char* part : {"command", "args"})
    if (container[part])
      for (const auto& word : container[part]) out.push_back(word.as<std::string>());
  return out;
}

std::optional<std::string> flag(const std::vector<std::string>& line, const std::string& name) {
  const std::string prefix = name + "=";
  for (std::size_t k = 0; k < line.size(); ++k) {
    if (line[k].starts_with(prefix)) return line[k].substr(prefix.size());
    if (line[k] == name && k + 1 < line.size()) return line[k + 1];
  }
  return std::nullopt;
}

YAML::Node with_merge_keys(const YAML::Node& map) {
  YAML::Node out(YAML::NodeType::Map);
  if (map["<<"])
    for (const auto& entry : map["<<"]) out[entry.first.as<std::string>()] = entry.second;
  for (const auto& entry : map)
    if (entry.first.as<std::string>() != "<<") out[entry.first.as<std::string>()] = entry.second;
  return out;
}

const std::vector<std::string>& client_flags() {
  static const std::vector<std::string> flags = {
      "--store",   "--sim-address", "--sim", "--approach",  "--manipulate",
      "--retract", "--hlc",         "--e2e", "--inference", "--controller"};
  return flags;
}

std::vector<std::pair<std::string, std::string>> client_targets(
    const std::vector<std::string>& line) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const std::string& f : client_flags())
    if (const auto target = flag(line, f)) out.emplace_back(f, *target);
  return out;
}

std::vector<int> container_ports(const YAML::Node& container) {
  std::vector<int> out;
  if (container["ports"])
    for (const auto& port : container["ports"]) out.push_back(port["containerPort"].as<int>());
  return out;
}

int port_of(const std::string& address) {
  const auto colon = address.rfind(':');
  if (colon == std::string::npos) return -1;
  try {
    return std::stoi(address.substr(colon + 1));
  } catch (const std::exception&) {
    return -1;
  }
}

std::string host_of(const std::string& target) {
  std::string name = target.starts_with("dns:///") ? target.substr(7) : target;
  return name.substr(0, name.rfind(':'));
}

long long millicores(const std::string& cpu) {
  if (cpu.ends_with("m")) return std::stoll(cpu.substr(0, cpu.size() - 1));
  return static_cast<long long>(std::stod(cpu) * 1000);
}

long long mebibytes(const std::string& memory) {
  if (memory.ends_with("Gi")) return std::stoll(memory.substr(0, memory.size() - 2)) * 1024;
  if (memory.ends_with("Mi")) return std::stoll(memory.substr(0, memory.size() - 2));
  throw std::invalid_argument("memory quantity in Mi or Gi expected, got " + memory);
}

bool may_connect(const std::vector<YAML::Node>& policies, const Labels& client,
                 const Labels& server, int port) {
  bool isolated = false;
  for (const YAML::Node& policy : policies) {
    bool ingress = !policy["spec"]["policyTypes"];  // absent: Ingress (and Egress if rules)
    for (const auto& type : policy["spec"]["policyTypes"])
      ingress = ingress || type.as<std::string>() == "Ingress";
    if (!ingress) continue;
    const Labels picks = simple_selector(policy["spec"]["podSelector"]);
    if (!picks.empty() && !selects(picks, server)) continue;  // {} picks every Pod
    isolated = true;
    if (!policy["spec"]["ingress"]) continue;
    for (const auto& rule : policy["spec"]["ingress"]) {
      bool from = !rule["from"] || rule["from"].size() == 0;  // no peers listed: every source
      if (!from)
        for (const auto& peer : rule["from"]) from = from || peer_matches(peer, client);
      bool ports = !rule["ports"] || rule["ports"].size() == 0;
      if (!ports)
        for (const auto& p : rule["ports"]) ports = ports || port_matches(p, port);
      if (from && ports) return true;
    }
  }
  return !isolated;
}

std::optional<int> probed_port(const std::vector<std::string>& command, const std::string& name) {
  const auto address = flag(command, "--" + name);
  if (!address || !address->starts_with("127.0.0.1:")) return std::nullopt;
  if (flag(command, "--only") != name) return std::nullopt;
  return port_of(*address);
}

std::vector<std::string> dev_certificate_names(const std::filesystem::path& script) {
  const std::string text = read_file(script);
  auto start = text.find("names=(");  // the default list: the first one that is not empty
  while (start != std::string::npos && text.compare(start + 7, 1, ")") == 0)
    start = text.find("names=(", start + 1);
  if (start == std::string::npos) throw std::runtime_error(script.string() + ": no names=(...)");
  const auto end = text.find(')', start);
  std::istringstream words(text.substr(start + 7, end - start - 7));
  std::vector<std::string> names;
  for (std::string word; words >> word;) {
    if (word.size() >= 2 && word.front() == '\'' && word.back() == '\'')
      word = word.substr(1, word.size() - 2);
    names.push_back(word);
  }
  return names;
}

bool certificate_covers(const std::vector<std::string>& names, const std::string& host) {
  for (const std::string& name : names) {
    if (name == host) return true;
    // "*.pnp" covers "pnp-inference.pnp": exactly one label in place of the star.
    if (name.starts_with("*.")) {
      const auto dot = host.find('.');
      if (dot != std::string::npos && dot > 0 && host.substr(dot) == name.substr(1)) return true;
    }
  }
  return false;
}

std::vector<std::string> scalars(const YAML::Node& node) {
  std::vector<std::string> out;
  const std::function<void(const YAML::Node&)> walk = [&](const YAML::Node& n) {
    if (n.IsScalar()) {
      out.push_back(n.as<std::string>());
    } else if (n.IsSequence()) {
      for (const auto& item : n) walk(item);
    } else if (n.IsMap()) {
      for (const auto& entry : n) {
        walk(entry.first);
        walk(entry.second);
      }
    }
  };
  walk(node);
  return out;
}

std::set<std::string> files_named(const std::vector<std::string>& texts,
                                  const std::string& extension) {
  const std::string suffix = "." + extension;
  const auto in_name = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '.' || c == '_' || c == '-';
  };
  std::set<std::string> out;
  for (const std::string& text : texts) {
    for (std::size_t begin = 0; begin < text.size();) {
      std::size_t end = begin;
      while (end < text.size() && in_name(text[end])) ++end;
      const std::string word = text.substr(begin, end - begin);
      if (word.size() > suffix.size() && word.ends_with(suffix))
        out.insert(word.substr(0, word.size() - suffix.size()));
      begin = end + 1;
    }
  }
  return out;
}

CommandOutput run_command(const std::string& command) {
  CommandOutput out;
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(::popen(command.c_str(), "r"), ::pclose);
  if (!pipe) throw std::runtime_error("cannot run " + command);
  std::array<char, 4096> buffer{};
  for (std::size_t n; (n = std::fread(buffer.data(), 1, buffer.size(), pipe.get())) > 0;)
    out.out.append(buffer.data(), n);
  const int status = ::pclose(pipe.release());
  out.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return out;
}

const std::map<std::string, std::string>& compose_identities() {
  static const std::map<std::string, std::string> identities = {{"store", "store"},
                                                                {"sim", "sim"},
                                                                {"approach", "approach"},
                                                                {"manipulate", "manipulate"},
                                                                {"retract", "retract"},
                                                                {"hlc", "hlc"},
                                                                {"e2e", "e2e"},
                                                                {"inference", "inference"},
                                                                {"robot-sim", "robot-sim"},
                                                                {"dashboard", "dashboard"},
                                                                {"gateway", "gateway"},
                                                                {"pipeline", "ops"}};
  return identities;
}

const std::map<std::string, std::string>& workload_identities() {
  static const std::map<std::string, std::string> identities = {
      {"pnp-store", "store"},       {"pnp-sim", "sim"},
      {"pnp-approach", "approach"}, {"pnp-manipulate", "manipulate"},
      {"pnp-retract", "retract"},   {"pnp-hlc", "hlc"},
      {"pnp-e2e", "e2e"},           {"pnp-inference", "inference"},
      {"pnp-pipeline", "ops"}};
  return identities;
}

const std::map<std::string, std::set<std::string>>& identity_classes() {
  static const std::set<std::string> trainer = {"reader", "agent", "service"};
  static const std::map<std::string, std::set<std::string>> classes = {
      {"store", {"reader"}},
      {"sim", {"reader"}},
      {"approach", trainer},
      {"manipulate", trainer},
      {"retract", trainer},
      {"hlc", trainer},
      {"e2e", trainer},
      {"inference", {"reader", "service", "delegate"}},
      {"robot-sim", {"reader", "service"}},
      {"dashboard", {"reader", "agent"}},
      {"gateway", {"reader", "agent", "robot"}},
      {"ops", {"reader", "agent", "operator"}},
      {"reader", {"reader"}},
      {"trainer", trainer}};
  return classes;
}

const std::set<std::string>& client_principals() {
  static const std::set<std::string> clients = {"ops", "gateway", "trainer", "reader"};
  return clients;
}

}  // namespace pnp::deploy_test
