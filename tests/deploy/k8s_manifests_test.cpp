// deploy/k8s, checked offline: every overlay renders with `kubectl kustomize`, and the
// rendered objects (plus the pipeline Job, applied on its own) keep the topology's
// invariants: one writer of the one volume, probes and limits on every server, Services
// that select Pods listening on their ports, flags and ports that agree, autoscaling and
// disruption budgets on real workloads, network policies that allow exactly the edges the
// servers' flags need, and a single-node overlay whose requests fit its node. Least
// privilege: each Pod mounts its own identity's Secret only (the ops Secret only the
// pipeline Job), serves and calls as that identity, no object names the CA key, and the
// README makes each Secret from its own bundle.
#include <fnmatch.h>
#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>

#include "tests/deploy/manifest_objects.h"

namespace pnp::deploy_test {
namespace {

const std::filesystem::path kK8s = std::filesystem::path(PNP_SOURCE_DIR) / "deploy" / "k8s";

class Overlay : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    const Rendered rendered = kustomize(kK8s / "overlays" / GetParam());
    ASSERT_EQ(rendered.exit_code, 0)
        << PNP_KUBECTL << " kustomize overlays/" << GetParam() << ": " << rendered.errors;
    objects_ = rendered.objects;
    for (const YAML::Node& job : load_all(kK8s / "job-pipeline.yaml")) objects_.push_back(job);
    workloads_ = workloads(objects_);
    services_ = of_kind(objects_, "Service");
  }

  // Each container of each workload with its workload.
  template <typename F>
  void for_each_container(F&& f) const {
    for (const Workload& w : workloads_)
      for (const auto& c : w.pod_spec["containers"]) f(w, c);
  }
  const Workload* workload(const std::string& name) const {
    for (const Workload& w : workloads_)
      if (w.name == name) return &w;
    return nullptr;
  }
  std::vector<const Workload*> selected_by(const Labels& selector) const {
    std::vector<const Workload*> out;
    for (const Workload& w : workloads_)
      if (selects(selector, w.pod_labels)) out.push_back(&w);
    return out;
  }
  const YAML::Node* service(const std::string& name) const {
    for (const YAML::Node& s : services_)
      if (s["metadata"]["name"].as<std::string>() == name) return &s;
    return nullptr;
  }

  const YAML::Node* config_map(const std::string& name) const {
    for (const YAML::Node& object : objects_)
      if (object["kind"].as<std::string>() == "ConfigMap" &&
          object["metadata"]["name"].as<std::string>() == name)
        return &object;
    return nullptr;
  }
  // A container's environment as the kubelet sets it: its envFrom ConfigMaps, then env.
  std::map<std::string, std::string> environment_of(const YAML::Node& container) const {
    std::map<std::string, std::string> out;
    for (const YAML::Node& from : list(container, "envFrom")) {
      if (!from["configMapRef"]) continue;
      if (const YAML::Node* map = config_map(from["configMapRef"]["name"].as<std::string>()))
        for (const auto& entry : (*map)["data"])
          out[entry.first.as<std::string>()] = entry.second.as<std::string>();
    }
    for (const YAML::Node& e : list(container, "env"))
      if (e["value"]) out[e["name"].as<std::string>()] = e["value"].as<std::string>();
    return out;
  }
  // The Secrets (kind "Secret") or ConfigMaps a workload's Pods read: volumes (projected
  // too), envFrom, env valueFrom.
  std::set<std::string> referenced(const Workload& w, const std::string& kind) const {
    const bool secret = kind == "Secret";
    const char* volume_key = secret ? "secret" : "configMap";
    const char* name_key = secret ? "secretName" : "name";
    std::set<std::string> out;
    for (const YAML::Node& v : list(w.pod_spec, "volumes")) {
      if (v[volume_key]) out.insert(v[volume_key][name_key].as<std::string>());
      if (v["projected"])
        for (const YAML::Node& source : list(v["projected"], "sources"))
          if (source[volume_key]) out.insert(source[volume_key]["name"].as<std::string>());
    }
    for (const char* containers : {"containers", "initContainers"}) {
      for (const YAML::Node& c : list(w.pod_spec, containers)) {
        for (const YAML::Node& from : list(c, "envFrom"))
          if (from[secret ? "secretRef" : "configMapRef"])
            out.insert(from[secret ? "secretRef" : "configMapRef"]["name"].as<std::string>());
        for (const YAML::Node& e : list(c, "env")) {
          const char* ref = secret ? "secretKeyRef" : "configMapKeyRef";
          if (e["valueFrom"] && e["valueFrom"][ref])
            out.insert(e["valueFrom"][ref]["name"].as<std::string>());
        }
      }
    }
    return out;
  }
  // The items of a list field; none when it is absent.
  static std::vector<YAML::Node> list(const YAML::Node& map, const char* field) {
    std::vector<YAML::Node> out;
    if (map && map.IsMap() && map[field] && map[field].IsSequence())
      for (const auto& item : map[field]) out.push_back(item);
    return out;
  }
  // Everything a workload's Pods are given: their template and the rendered ConfigMaps
  // they read.
  std::vector<std::string> holdings(const Workload& w) const {
    std::vector<std::string> out = scalars(w.object["spec"]["template"]);
    for (const std::string& name : referenced(w, "ConfigMap"))
      if (const YAML::Node* map = config_map(name))
        for (const std::string& text : scalars(*map)) out.push_back(text);
    return out;
  }
  // Where a container mounts the volume made from Secret `secret`; empty if it does not.
  static std::string mount_of(const Workload& w, const YAML::Node& container,
                              const std::string& secret) {
    for (const YAML::Node& v : list(w.pod_spec, "volumes")) {
      if (!v["secret"] || v["secret"]["secretName"].as<std::string>() != secret) continue;
      for (const YAML::Node& mount : list(container, "volumeMounts"))
        if (mount["name"].as<std::string>() == v["name"].as<std::string>())
          return mount["mountPath"].as<std::string>();
    }
    return "";
  }

  std::vector<YAML::Node> objects_;
  std::vector<Workload> workloads_;
  std::vector<YAML::Node> services_;
};

TEST_P(Overlay, OnlyTheStoreHasTheVolumeAndTheDatabase) {
  EXPECT_TRUE(of_kind(objects_, "PersistentVolumeClaim").empty())
      << "a free-standing claim: any Pod could mount it";
  std::vector<std::string> with_claims, with_db;
  for (const Workload& w : workloads_) {
    if (w.object["spec"]["volumeClaimTemplates"]) with_claims.push_back(w.name);
    if (w.pod_spec["volumes"]) {
      for (const auto& v : w.pod_spec["volumes"]) {
        EXPECT_FALSE(v["persistentVolumeClaim"] || v["hostPath"] || v["nfs"])
            << w.name << " mounts shared storage " << v["name"].as<std::string>();
      }
    }
  }
  for_each_container([&](const Workload& w, const YAML::Node& c) {
    const auto line = command_line(c);
    if (flag(line, "--db")) with_db.push_back(w.name);
  });
  ASSERT_EQ(with_claims, std::vector<std::string>{"pnp-store"});
  EXPECT_EQ(with_db, std::vector<std::string>{"pnp-store"});
  const Workload& store = *workload("pnp-store");
  EXPECT_EQ(store.kind, "StatefulSet");
  EXPECT_EQ(store.replicas, 1) << "two store Pods would be two SQLite writers";
  // The database is on the claim.
  const YAML::Node container = store.pod_spec["containers"][0];
  const std::string db = *flag(command_line(container), "--db");
  bool on_claim = false;
  for (const auto& mount : container["volumeMounts"]) {
    if (mount["name"].as<std::string>() == "data")
      on_claim = db.starts_with(mount["mountPath"].as<std::string>() + "/");
  }
  EXPECT_TRUE(on_claim) << db;
}

TEST_P(Overlay, EveryServerHasProbesRequestsAndLimits) {
  for_each_container([&](const Workload& w, const YAML::Node& c) {
    const std::string where = w.name + "/" + c["name"].as<std::string>();
    if (w.kind != "Job") {
      EXPECT_TRUE(c["readinessProbe"]) << where;
      EXPECT_TRUE(c["livenessProbe"]) << where;
    }
    for (const char* resource : {"cpu", "memory"}) {
      const YAML::Node request = c["resources"]["requests"][resource];
      const YAML::Node limit = c["resources"]["limits"][resource];
      ASSERT_TRUE(request && limit) << where << " has no " << resource << " request or limit";
      const bool cpu = std::string(resource) == "cpu";
      const auto amount = [&](const YAML::Node& q) {
        return cpu ? millicores(q.as<std::string>()) : mebibytes(q.as<std::string>());
      };
      EXPECT_LE(amount(request), amount(limit)) << where << " " << resource;
    }
    EXPECT_EQ(c["securityContext"]["readOnlyRootFilesystem"].as<bool>(false), true) << where;
    EXPECT_EQ(w.pod_spec["securityContext"]["runAsNonRoot"].as<bool>(false), true) << where;
  });
}

TEST_P(Overlay, EveryServiceSelectsPodsListeningOnItsPorts) {
  for (const YAML::Node& s : of_kind(objects_, "Service")) {
    const std::string name = s["metadata"]["name"].as<std::string>();
    const auto pods = selected_by(labels_of(s["spec"]["selector"]));
    ASSERT_FALSE(pods.empty()) << "Service " << name << " selects no Pod";
    for (const auto& port : s["spec"]["ports"]) {
      const int target = port["targetPort"].as<int>();
      for (const Workload* w : pods) {
        std::set<int> listening;
        for (const auto& c : w->pod_spec["containers"])
          for (const int p : container_ports(c)) listening.insert(p);
        EXPECT_TRUE(listening.contains(target))
            << "Service " << name << " sends port " << target << " to " << w->name;
      }
    }
  }
}

TEST_P(Overlay, PortsAgreeWithTheServersFlags) {
  for_each_container([&](const Workload& w, const YAML::Node& c) {
    const auto line = command_line(c);
    const std::string where = w.name + "/" + c["name"].as<std::string>();
    const auto ports = container_ports(c);
    const auto listens_on = [&](const std::string& f) {
      const auto address = flag(line, f);
      if (!address) return;
      EXPECT_TRUE(address->starts_with("0.0.0.0:")) << where << " " << f << " " << *address;
      EXPECT_NE(std::find(ports.begin(), ports.end(), port_of(*address)), ports.end())
          << where << " " << f << "=" << *address << " is not a containerPort";
    };
    listens_on("--address");
    listens_on("--metrics-address");
    // The probes check this container's own server, by its name and port.
    if (const auto address = flag(line, "--address")) {
      for (const char* probe : {"readinessProbe", "livenessProbe"}) {
        if (!c[probe]) continue;  // EveryServerHasProbesRequestsAndLimits says so
        std::vector<std::string> command;
        for (const auto& word : c[probe]["exec"]["command"])
          command.push_back(word.as<std::string>());
        EXPECT_EQ(probed_port(command, c["name"].as<std::string>()), port_of(*address))
            << where << " " << probe << " does not check this server";
      }
    }
    // A client flag names a Service with that port; dns:/// (the client balances over
    // every Pod) needs a headless one.
    for (const auto& [f, target] : client_targets(line)) {
      const YAML::Node* s = service(host_of(target));
      ASSERT_NE(s, nullptr) << where << " " << f << "=" << target << ": no such Service";
      bool has_port = false;
      for (const auto& p : (*s)["spec"]["ports"])
        has_port |= p["port"].as<int>() == port_of(target);
      EXPECT_TRUE(has_port) << where << " " << f << "=" << target;
      if (target.starts_with("dns:///")) {
        EXPECT_EQ((*s)["spec"]["clusterIP"].as<std::string>(""), "None") << where << " " << f;
      }
    }
  });
}

TEST_P(Overlay, AutoscalersAndDisruptionBudgetsTargetRealWorkloads) {
  const auto autoscalers = of_kind(objects_, "HorizontalPodAutoscaler");
  ASSERT_FALSE(autoscalers.empty());
  for (const YAML::Node& hpa : autoscalers) {
    const Workload* target = workload(hpa["spec"]["scaleTargetRef"]["name"].as<std::string>());
    ASSERT_NE(target, nullptr);
    EXPECT_EQ(target->kind, hpa["spec"]["scaleTargetRef"]["kind"].as<std::string>());
    EXPECT_FALSE(target->has_replicas) << target->name << ": replicas would fight the autoscaler";
    EXPECT_LE(hpa["spec"]["minReplicas"].as<int>(), hpa["spec"]["maxReplicas"].as<int>());
    for (const auto& c : target->pod_spec["containers"])
      EXPECT_TRUE(c["resources"]["requests"]["cpu"]) << "CPU utilisation needs a CPU request";
  }
  for (const YAML::Node& pdb : of_kind(objects_, "PodDisruptionBudget")) {
    const auto pods = selected_by(labels_of(pdb["spec"]["selector"]["matchLabels"]));
    EXPECT_EQ(pods.size(), 1u) << pdb["metadata"]["name"].as<std::string>();
    EXPECT_TRUE(pdb["spec"]["maxUnavailable"]) << "minAvailable could block every drain";
    for (const Workload* w : pods) EXPECT_NE(w->name, "pnp-store");
  }
}

// Every edge a flag implies is open; the store, simulation and training ports are closed
// to every Pod without the flag that needs them.
TEST_P(Overlay, NetworkPoliciesAllowExactlyTheEdgesTheFlagsNeed) {
  const auto policies = of_kind(objects_, "NetworkPolicy");
  ASSERT_FALSE(policies.empty());
  std::map<std::string, std::set<std::string>> clients_of;  // server workload -> clients
  for_each_container([&](const Workload& w, const YAML::Node& c) {
    const auto line = command_line(c);
    for (const auto& [f, target] : client_targets(line)) {
      const YAML::Node* s = service(host_of(target));
      ASSERT_NE(s, nullptr) << target;
      for (const Workload* server : selected_by(labels_of((*s)["spec"]["selector"]))) {
        EXPECT_TRUE(may_connect(policies, w.pod_labels, server->pod_labels, port_of(target)))
            << w.name << " cannot reach " << server->name << " for " << f << "=" << target;
        clients_of[server->name].insert(w.name);
      }
    }
  });
  for (const std::string server : {"pnp-store", "pnp-sim", "pnp-approach", "pnp-hlc"}) {
    const Workload& s = *workload(server);
    const int port = container_ports(s.pod_spec["containers"][0]).front();
    for (const Workload& w : workloads_) {
      if (w.name == server || clients_of[server].contains(w.name)) continue;
      EXPECT_FALSE(may_connect(policies, w.pod_labels, s.pod_labels, port))
          << w.name << " can reach " << server << ":" << port << " without needing it";
    }
    // Nor can a stranger's Pod.
    EXPECT_FALSE(may_connect(policies, {{"app", "stranger"}}, s.pod_labels, port)) << server;
  }
  EXPECT_TRUE(
      may_connect(policies, {{"app", "stranger"}}, workload("pnp-inference")->pod_labels, 50060))
      << "robots' gateways reach inference from anywhere";
}

// `$(NAME)` in a command line is expanded by the kubelet from the container's environment:
// a name it does not have would be passed on literally.
TEST_P(Overlay, EveryVariableACommandUsesIsInTheContainersEnvironment) {
  std::map<std::string, std::set<std::string>> config_maps;
  for (const YAML::Node& map : of_kind(objects_, "ConfigMap"))
    for (const auto& entry : map["data"])
      config_maps[map["metadata"]["name"].as<std::string>()].insert(entry.first.as<std::string>());
  int uses = 0;
  for_each_container([&](const Workload& w, const YAML::Node& c) {
    std::set<std::string> environment;
    if (c["env"])
      for (const auto& e : c["env"]) environment.insert(e["name"].as<std::string>());
    if (c["envFrom"])
      for (const auto& from : c["envFrom"])
        for (const auto& key : config_maps[from["configMapRef"]["name"].as<std::string>()])
          environment.insert(key);
    for (const std::string& word : command_line(c)) {
      for (auto at = word.find("$("); at != std::string::npos; at = word.find("$(", at + 2)) {
        const std::string name = word.substr(at + 2, word.find(')', at) - at - 2);
        EXPECT_TRUE(environment.contains(name)) << w.name << ": $(" << name << ") is not set";
        ++uses;
      }
    }
  });
  EXPECT_GT(uses, 0);  // the trainers' --threads=$(PNP_TRAIN_THREADS)
}

// Clients verify the server certificate against the name they dial: the development
// certificates (scripts/make-dev-certs) carry every one, also as dialled from another
// namespace.
TEST_P(Overlay, EveryNameAClientDialsIsOnTheDevelopmentCertificate) {
  const auto names =
      dev_certificate_names(std::filesystem::path(PNP_SOURCE_DIR) / "scripts" / "make-dev-certs");
  for_each_container([&](const Workload& w, const YAML::Node& c) {
    const auto line = command_line(c);
    for (const auto& [f, target] : client_targets(line)) {
      const std::string host = host_of(target);
      EXPECT_TRUE(certificate_covers(names, host)) << w.name << " dials " << host;
      EXPECT_TRUE(certificate_covers(names, host + ".pnp")) << host << ".pnp";
      EXPECT_TRUE(certificate_covers(names, host + ".pnp.svc.cluster.local")) << host;
    }
  });
}

TEST_P(Overlay, EveryContainerRunsTheOneImage) {
  std::set<std::string> images;
  for_each_container(
      [&](const Workload&, const YAML::Node& c) { images.insert(c["image"].as<std::string>()); });
  EXPECT_EQ(images.size(), 1u) << "the Job and the servers must run the same build";
}

// Breaking into one Pod must not yield the CA key (hence any identity): no object names it.
TEST_P(Overlay, NoObjectNamesTheCaKey) {
  for (const YAML::Node& object : objects_)
    EXPECT_FALSE(files_named(scalars(object), "key").contains("ca"))
        << object["kind"].as<std::string>() << " " << object["metadata"]["name"].as<std::string>();
}

// Each Pod mounts one Secret, its own identity's (pnp-identity-NAME), and names no file of
// another identity; only the pipeline Job has the ops (operator) credentials.
TEST_P(Overlay, EachPodHoldsItsOwnIdentityAndNoOther) {
  std::set<std::string> with_ops;
  for (const Workload& w : workloads_) {
    const auto identity = workload_identities().find(w.name);
    ASSERT_NE(identity, workload_identities().end())
        << w.name << ": give it an identity (tests/deploy/manifest_objects.cpp)";
    const std::string& own = identity->second;
    EXPECT_EQ(referenced(w, "Secret"), std::set<std::string>{"pnp-identity-" + own})
        << w.name << " must mount its own identity's Secret and no other";
    const auto held = holdings(w);
    for (const std::string& key : files_named(held, "key"))
      EXPECT_EQ(key, own) << w.name << " names " << key << ".key";
    for (const std::string& token : files_named(held, "token"))
      EXPECT_EQ(token, own) << w.name << " names " << token << ".token";
    for (const std::string& certificate : files_named(held, "pem"))
      EXPECT_TRUE(certificate == own || certificate == "ca")
          << w.name << " names " << certificate << ".pem";
    if (referenced(w, "Secret").contains("pnp-identity-ops") ||
        files_named(held, "key").contains("ops"))
      with_ops.insert(w.name);
  }
  EXPECT_EQ(with_ops, std::set<std::string>{"pnp-pipeline"}) << "operator credentials";
}

// Each server serves with its own certificate from its own Secret, and its probes, store
// client and simulation client present the same identity; the pipeline calls as ops.
TEST_P(Overlay, EachServerServesWithItsOwnCertificateAndCallsAsItself) {
  int servers = 0;
  for_each_container([&](const Workload& w, const YAML::Node& c) {
    const std::string own = workload_identities().at(w.name);
    const std::string dir = mount_of(w, c, "pnp-identity-" + own);
    ASSERT_FALSE(dir.empty()) << w.name << " does not mount pnp-identity-" << own;
    const auto env = environment_of(c);
    const auto variable = [&](const std::string& key) {
      return env.contains(key) ? env.at(key) : std::string("(unset)");
    };
    const auto line = command_line(c);
    std::vector<std::string> clients = {"PNP_TLS"};  // the probes' pnpctl, or the Job's
    if (flag(line, "--address")) {
      ++servers;
      EXPECT_EQ(flag(line, "--tls-cert").value_or(variable("PNP_SERVER_TLS_CERT")),
                dir + "/" + own + ".pem")
          << w.name << " does not serve with its own certificate";
      EXPECT_EQ(flag(line, "--tls-key").value_or(variable("PNP_SERVER_TLS_KEY")),
                dir + "/" + own + ".key")
          << w.name;
    }
    if (flag(line, "--store")) clients.push_back("PNP_STORE_TLS");
    if (flag(line, "--sim-address")) clients.push_back("PNP_SIM_TLS");
    for (const std::string& client : clients) {
      EXPECT_EQ(variable(client + "_CERT"), dir + "/" + own + ".pem") << w.name << " " << client;
      EXPECT_EQ(variable(client + "_KEY"), dir + "/" + own + ".key") << w.name << " " << client;
    }
  });
  EXPECT_EQ(servers, 8);  // store, sim, five trainers, inference
}

INSTANTIATE_TEST_SUITE_P(K8s, Overlay, ::testing::Values("single-node", "cluster"),
                         [](const auto& overlay) {
                           std::string name = overlay.param;
                           std::erase(name, '-');
                           return name;
                         });

// One node of 2 cores and 4 GiB (overlays/single-node/kustomization.yaml): the requests,
// with every autoscaled tier at its maximum, leave a quarter for the node's own daemons,
// and no limit asks for more than the node has.
TEST(SingleNodeOverlay, RequestsFitItsNode) {
  const Rendered rendered = kustomize(kK8s / "overlays" / "single-node");
  ASSERT_EQ(rendered.exit_code, 0) << rendered.errors;
  std::map<std::string, int> autoscaled;
  for (const YAML::Node& hpa : of_kind(rendered.objects, "HorizontalPodAutoscaler"))
    autoscaled[hpa["spec"]["scaleTargetRef"]["name"].as<std::string>()] =
        hpa["spec"]["maxReplicas"].as<int>();
  long long cpu = 0, memory = 0;
  for (const Workload& w : workloads(rendered.objects)) {
    const int replicas = autoscaled.contains(w.name) ? autoscaled[w.name] : w.replicas;
    for (const auto& c : w.pod_spec["containers"]) {
      cpu += replicas * millicores(c["resources"]["requests"]["cpu"].as<std::string>());
      memory += replicas * mebibytes(c["resources"]["requests"]["memory"].as<std::string>());
      EXPECT_LE(millicores(c["resources"]["limits"]["cpu"].as<std::string>()), 2000) << w.name;
      EXPECT_LE(mebibytes(c["resources"]["limits"]["memory"].as<std::string>()), 4096) << w.name;
    }
  }
  std::printf("[ measured ] single-node requests: %lld mCPU, %lld MiB\n", cpu, memory);
  EXPECT_LE(cpu, 1500);
  EXPECT_LE(memory, 3072);
}

// deploy/README.md's steps: each identity Secret is made from that identity's bundle
// (dev-certs/bundles/NAME/, which never holds the CA key), every Secret and ConfigMap a Pod
// needs that the overlays do not render is made there, and no step hands out or exposes
// dev-certs/ca.key (a whole dev-certs/ folder, or a glob that matches it).
TEST(DeployReadme, MakesEachSecretFromItsOwnBundleAndNeverHandsOutTheCaKey) {
  std::ifstream in(std::filesystem::path(PNP_SOURCE_DIR) / "deploy" / "README.md");
  std::set<std::string> made;
  for (std::string text; std::getline(in, text);) {
    std::istringstream split(text);
    std::vector<std::string> words;
    for (std::string word; split >> word;) words.push_back(word);
    for (std::string word : words) {
      if (word.starts_with("--from-file=")) word = word.substr(12);
      if (const auto equals = word.find('='); equals != std::string::npos && !word.starts_with("-"))
        word = word.substr(equals + 1);  // --from-file=KEY=PATH
      word.erase(0, word.find_first_not_of("`"));
      if (!word.starts_with("dev-certs")) continue;
      const bool whole_folder = word == "dev-certs" || word == "dev-certs/";
      EXPECT_FALSE(whole_folder && text.find("make-dev-certs") == std::string::npos)
          << "the whole dev-certs folder holds ca.key: " << text;
      EXPECT_NE(::fnmatch(word.c_str(), "dev-certs/ca.key", FNM_PATHNAME), 0)
          << word << " takes in ca.key: " << text;
    }
    for (std::size_t k = 0; k + 3 < words.size(); ++k) {
      if (words[k] != "create") continue;
      const bool secret = words[k + 1] == "secret" && words[k + 2] == "generic";
      if (!secret && words[k + 1] != "configmap") continue;
      const std::string name = words[k + (secret ? 3 : 2)];
      made.insert(name);
      if (!secret) continue;
      ASSERT_TRUE(name.starts_with("pnp-identity-")) << "a Secret of one identity: " << text;
      const std::string bundle = "dev-certs/bundles/" + name.substr(13) + "/";
      int sources = 0;
      for (const std::string& word : words) {
        if (!word.starts_with("--from-file=")) continue;
        ++sources;
        EXPECT_TRUE(word.substr(12).starts_with(bundle))
            << name << " must be made from " << bundle << " only: " << text;
      }
      EXPECT_GT(sources, 0) << text;
    }
  }
  // Every Secret or ConfigMap a Pod reads exists: rendered, or made by these steps.
  for (const std::string overlay : {"single-node", "cluster"}) {
    const Rendered rendered = kustomize(kK8s / "overlays" / overlay);
    ASSERT_EQ(rendered.exit_code, 0) << rendered.errors;
    auto objects = rendered.objects;
    for (const YAML::Node& job : load_all(kK8s / "job-pipeline.yaml")) objects.push_back(job);
    std::set<std::string> rendered_maps;
    for (const YAML::Node& map : of_kind(objects, "ConfigMap"))
      rendered_maps.insert(map["metadata"]["name"].as<std::string>());
    for (const Workload& w : workloads(objects)) {
      if (!w.pod_spec["volumes"]) continue;
      for (const auto& v : w.pod_spec["volumes"]) {
        if (v["secret"]) {
          const auto name = v["secret"]["secretName"].as<std::string>();
          EXPECT_TRUE(made.contains(name)) << w.name << " mounts " << name << ", made nowhere";
        }
        if (v["configMap"]) {
          const auto name = v["configMap"]["name"].as<std::string>();
          EXPECT_TRUE(made.contains(name) || rendered_maps.contains(name))
              << w.name << " mounts " << name << ", made nowhere";
        }
      }
    }
  }
}

}  // namespace
}  // namespace pnp::deploy_test
