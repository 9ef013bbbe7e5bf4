// deploy/docker-compose.yml in the Kubernetes files' topology: only the store server has
// the database and its volume, every client flag names a service listening on that port,
// every server is health-checked on its own port, published ports stay on loopback, and
// each server listens where its Kubernetes twin does.
#include <gtest/gtest.h>

#include <set>

#include "tests/deploy/manifest_objects.h"

namespace pnp::deploy_test {
namespace {

const std::filesystem::path kDeploy = std::filesystem::path(PNP_SOURCE_DIR) / "deploy";

class ComposeFile : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto documents = load_all(kDeploy / "docker-compose.yml");
    ASSERT_EQ(documents.size(), 1u);
    for (const auto& entry : documents[0]["services"]) {
      const auto name = entry.first.as<std::string>();
      services_[name] = with_merge_keys(entry.second);
      for (const auto& word : services_[name]["command"])
        commands_[name].push_back(word.as<std::string>());
    }
  }
  // The port a service's server listens on (--address), -1 if it is not a gRPC server.
  int listening_port(const std::string& service) const {
    const auto found = commands_.find(service);
    if (found == commands_.end()) return -1;
    const auto address = flag(found->second, "--address");
    return address ? port_of(*address) : -1;
  }

  std::map<std::string, YAML::Node> services_;
  std::map<std::string, std::vector<std::string>> commands_;
};

TEST_F(ComposeFile, OnlyTheStoreServerHasTheDatabaseAndItsVolume) {
  std::set<std::string> with_db, with_volume;
  for (const auto& [name, line] : commands_)
    if (flag(line, "--db")) with_db.insert(name);
  for (const auto& [name, service] : services_) {
    if (!service["volumes"]) continue;
    for (const auto& volume : service["volumes"])
      if (volume.as<std::string>().starts_with("pnp-data:")) with_volume.insert(name);
  }
  EXPECT_EQ(with_db, std::set<std::string>{"store"});
  EXPECT_EQ(with_volume, std::set<std::string>{"store"});
  EXPECT_EQ(commands_["store"].front(), "pnp-store-server");
  for (const auto& [name, line] : commands_) {
    // The robot controller has no store of its own, but its audit goes to the store's.
    const bool stateful_server = line.front() == "pnp-train-server" ||
                                 line.front() == "pnp-inference-server" ||
                                 line.front() == "pnp-dashboard" || line.front() == "pnp-robot-sim";
    if (stateful_server) {
      EXPECT_EQ(flag(line, "--store"), "store:50050") << name;
    }
  }
}

TEST_F(ComposeFile, EveryClientFlagNamesAServiceListeningThere) {
  for (const auto& [name, line] : commands_) {
    for (const auto& [f, target] : client_targets(line)) {
      const std::string host = host_of(target);
      ASSERT_TRUE(services_.contains(host)) << name << " " << f << " " << target;
      EXPECT_EQ(listening_port(host), port_of(target)) << name << " " << f << " " << target;
    }
  }
}

TEST_F(ComposeFile, EveryServerIsHealthCheckedOnItsOwnPortAndPublishedOnLoopbackOnly) {
  for (const auto& [name, service] : services_) {
    const std::vector<std::string>& line = commands_[name];
    const int port = listening_port(name);
    if (port > 0 && line.front() != "pnp-dashboard") {  // the dashboard serves HTTPS
      std::vector<std::string> test;
      for (const auto& word : service["healthcheck"]["test"])
        test.push_back(word.as<std::string>());
      std::optional<int> checked;
      for (const std::string& word : test)
        if (word.starts_with("127.0.0.1:")) checked = port_of(word);
      EXPECT_EQ(checked, port) << name << "'s healthcheck does not check its own port";
    }
    if (!service["ports"]) continue;
    const auto metrics = flag(line, "--metrics-address");
    for (const auto& published : service["ports"]) {
      const auto mapping = published.as<std::string>();
      EXPECT_TRUE(mapping.starts_with("127.0.0.1:")) << name << " publishes " << mapping;
      const int inside = port_of(mapping);
      EXPECT_TRUE(inside == port || (metrics && inside == port_of(*metrics)))
          << name << " publishes " << mapping << ", where nothing listens";
    }
  }
}

TEST_F(ComposeFile, EveryNameAClientDialsIsOnTheDevelopmentCertificate) {
  const auto names =
      dev_certificate_names(std::filesystem::path(PNP_SOURCE_DIR) / "scripts" / "make-dev-certs");
  for (const auto& [name, line] : commands_) {
    for (const auto& [f, target] : client_targets(line))
      EXPECT_TRUE(certificate_covers(names, host_of(target))) << name << " " << f;
  }
}

TEST_F(ComposeFile, EachServerListensWhereItsKubernetesTwinDoes) {
  const Rendered rendered = kustomize(kDeploy / "k8s" / "overlays" / "single-node");
  ASSERT_EQ(rendered.exit_code, 0) << rendered.errors;
  int compared = 0;
  for (const Workload& w : workloads(rendered.objects)) {
    const std::string twin = w.name.substr(std::string("pnp-").size());
    const auto line = command_line(w.pod_spec["containers"][0]);
    const auto address = flag(line, "--address");
    if (!address || !services_.contains(twin)) continue;
    EXPECT_EQ(listening_port(twin), port_of(*address)) << w.name;
    EXPECT_EQ(flag(commands_[twin], "--metrics-address"), flag(line, "--metrics-address"))
        << w.name;
    ++compared;
  }
  EXPECT_EQ(compared, 8);  // store, sim, five trainers, inference
}

}  // namespace
}  // namespace pnp::deploy_test
