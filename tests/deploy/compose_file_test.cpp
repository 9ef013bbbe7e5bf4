// deploy/docker-compose.yml in the Kubernetes files' topology: only the store server has
// the database and its volume, every client flag names a service listening on that port,
// every server is health-checked on its own port, published ports stay on loopback, and
// each server listens where its Kubernetes twin does. Least privilege: each service holds
// its own identity only (never the CA key, another's key or the operator's credentials)
// and serves and calls as it; and the identities scripts/make-dev-certs makes are those
// the files expect, named as they are dialled, with the classes the policy should give.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
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
    for (const auto& entry : documents[0]["secrets"])
      secret_files_[entry.first.as<std::string>()] = entry.second["file"].as<std::string>("");
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

  // The secrets a service lists (short or long syntax), by name.
  std::vector<std::string> secrets_of(const std::string& service) const {
    std::vector<std::string> out;
    const YAML::Node listed = services_.at(service)["secrets"];
    if (!listed) return out;
    for (const auto& secret : listed)
      out.push_back(secret.IsMap() ? secret["source"].as<std::string>() : secret.as<std::string>());
    return out;
  }
  // Everything a service is given: its own definition (environment, command, volumes) and
  // each secret it lists, by name and by the file it is made from.
  std::vector<std::string> holdings(const std::string& service) const {
    std::vector<std::string> out = scalars(services_.at(service));
    for (const std::string& secret : secrets_of(service)) {
      out.push_back(secret);
      if (secret_files_.contains(secret)) out.push_back(secret_files_.at(secret));
    }
    return out;
  }
  // Its environment, with the YAML merge key (`<<: *tls`) applied.
  std::map<std::string, std::string> environment(const std::string& service) const {
    std::map<std::string, std::string> out;
    const YAML::Node listed = services_.at(service)["environment"];
    if (!listed) return out;
    if (listed.IsSequence()) {
      for (const auto& item : listed) {
        const auto text = item.as<std::string>();
        const auto equals = text.find('=');
        out[text.substr(0, equals)] = equals == std::string::npos ? "" : text.substr(equals + 1);
      }
      return out;
    }
    for (const auto& entry : with_merge_keys(listed))
      out[entry.first.as<std::string>()] = entry.second.as<std::string>("");
    return out;
  }

  std::map<std::string, YAML::Node> services_;
  std::map<std::string, std::vector<std::string>> commands_;
  std::map<std::string, std::string> secret_files_;  // top-level secrets: name -> file
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

// Breaking into one container must not yield the CA key (hence any identity).
TEST_F(ComposeFile, NoServiceIsGivenTheCaKey) {
  for (const auto& [name, service] : services_)
    EXPECT_FALSE(files_named(holdings(name), "key").contains("ca")) << name << " holds ca.key";
  for (const auto& [secret, file] : secret_files_)
    EXPECT_FALSE(files_named({secret, file}, "key").contains("ca")) << "secret " << secret;
}

// Each service holds its own certificate and key (with the CA certificate and the policy),
// from its own bundle, and nothing of another identity; only the pipeline holds ops.
TEST_F(ComposeFile, EachServiceHoldsItsOwnIdentityAndNoOther) {
  std::set<std::string> with_ops;
  for (const auto& [name, service] : services_) {
    const auto identity = compose_identities().find(name);
    ASSERT_NE(identity, compose_identities().end())
        << name << ": give it an identity (tests/deploy/manifest_objects.cpp)";
    const std::string& own = identity->second;
    const auto held = holdings(name);
    EXPECT_EQ(files_named(held, "key"), std::set<std::string>{own}) << name << "'s keys";
    for (const std::string& token : files_named(held, "token"))
      EXPECT_EQ(token, own) << name << " holds " << token << ".token";
    for (const std::string& certificate : files_named(held, "pem"))
      EXPECT_TRUE(certificate == own || certificate == "ca")
          << name << " holds " << certificate << ".pem";
    for (const std::string& secret : secrets_of(name)) {
      const std::string file = secret_files_.contains(secret) ? secret_files_.at(secret) : "";
      EXPECT_FALSE(file.empty()) << name << ": secret " << secret << " has no file";
      if (secret.ends_with(".key")) {
        EXPECT_NE(file.find("/bundles/" + own + "/"), std::string::npos)
            << name << "'s " << secret << " is not from its own bundle: " << file;
      }
    }
    const std::vector<std::set<std::string>> named = {
        files_named(held, "key"), files_named(held, "pem"), files_named(held, "token")};
    for (const auto& stems : named)
      if (stems.contains("ops")) with_ops.insert(name);
  }
  EXPECT_EQ(with_ops, std::set<std::string>{"pipeline"}) << "operator credentials";
}

// Each server serves with its own certificate, and its health check, store client,
// simulation client and (the dashboard) platform client present that same identity.
TEST_F(ComposeFile, EachServerServesWithItsOwnCertificateAndCallsAsItself) {
  int servers = 0;
  for (const auto& [name, line] : commands_) {
    if (!flag(line, "--address")) continue;
    ++servers;
    const std::string own = compose_identities().at(name);
    const auto env = environment(name);
    const auto variable = [&](const std::string& key) {
      return env.contains(key) ? env.at(key) : std::string("(unset)");
    };
    // A flag wins over its variable.
    EXPECT_EQ(flag(line, "--tls-cert").value_or(variable("PNP_SERVER_TLS_CERT")),
              "/run/secrets/" + own + ".pem")
        << name << " does not serve with its own certificate";
    EXPECT_EQ(flag(line, "--tls-key").value_or(variable("PNP_SERVER_TLS_KEY")),
              "/run/secrets/" + own + ".key")
        << name;
    const auto secrets = secrets_of(name);
    for (const std::string& file : {own + ".pem", own + ".key"}) {
      EXPECT_NE(std::find(secrets.begin(), secrets.end(), file), secrets.end()) << name;
      EXPECT_TRUE(secret_files_.contains(file) && secret_files_.at(file).ends_with("/" + file))
          << name << ": " << file;
    }
    std::vector<std::string> clients;
    if (services_.at(name)["healthcheck"]) clients.push_back("PNP_TLS");
    if (flag(line, "--store")) clients.push_back("PNP_STORE_TLS");
    if (flag(line, "--sim-address")) clients.push_back("PNP_SIM_TLS");
    if (line.front() == "pnp-dashboard") clients.push_back("PNP_PLATFORM_TLS");
    for (const std::string& client : clients) {
      EXPECT_EQ(variable(client + "_CERT"), "/run/secrets/" + own + ".pem") << name;
      EXPECT_EQ(variable(client + "_KEY"), "/run/secrets/" + own + ".key") << name;
    }
  }
  // store, sim, five trainers, inference, robot-sim, dashboard
  EXPECT_EQ(servers, 10);
}

// What scripts/make-dev-certs makes, checked on a fresh set: one bundle per identity
// holding only that identity (never the CA key), the classes the policy gives each, and
// each server's certificate valid for every name it is dialled by in compose and in
// Kubernetes, and for its own health check on loopback.
class DevCertificates : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::filesystem::temp_directory_path() / ("pnp_dev_certs_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    const std::string command = std::string(PNP_SOURCE_DIR) + "/scripts/make-dev-certs --out '" +
                                dir_.string() + "' 2>/dev/null";
    made_ = std::system(command.c_str()) == 0;
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }
  void SetUp() override { ASSERT_TRUE(made_) << "scripts/make-dev-certs failed"; }

  // openssl's account of a certificate: subject, subject alternative names, key usage.
  static std::string describe(const std::string& identity) {
    const CommandOutput shown =
        run_command("openssl x509 -noout -subject -ext subjectAltName,extendedKeyUsage -in '" +
                    (dir_ / (identity + ".pem")).string() + "'");
    EXPECT_EQ(shown.exit_code, 0) << identity;
    return shown.out;
  }
  // Its subject alternative names: DNS names and IP addresses, without their prefixes.
  static std::set<std::string> alt_names(const std::string& described) {
    std::set<std::string> out;
    const auto header = described.find("Subject Alternative Name:");
    if (header == std::string::npos) return out;
    const auto begin = described.find('\n', header) + 1;
    std::string line = described.substr(begin, described.find('\n', begin) - begin);
    line += ",";
    for (std::size_t at = 0, comma; (comma = line.find(',', at)) != std::string::npos;
         at = comma + 1) {
      std::string entry = line.substr(at, comma - at);
      entry.erase(0, entry.find_first_not_of(' '));
      for (const char* prefix : {"DNS:", "IP Address:"})
        if (entry.starts_with(prefix)) out.insert(entry.substr(std::string(prefix).size()));
    }
    return out;
  }
  static std::set<std::string> server_identities() {
    std::set<std::string> out;
    for (const auto& [identity, classes] : identity_classes())
      if (!client_principals().contains(identity)) out.insert(identity);
    return out;
  }

  static inline std::filesystem::path dir_;
  static inline bool made_ = false;
};

TEST_F(DevCertificates, EachBundleHoldsOneIdentityAndNeverTheCaKey) {
  std::set<std::string> bundles;
  for (const auto& entry : std::filesystem::directory_iterator(dir_ / "bundles")) {
    const std::string identity = entry.path().filename().string();
    bundles.insert(identity);
    std::set<std::string> files;
    for (const auto& file : std::filesystem::recursive_directory_iterator(entry.path()))
      files.insert(std::filesystem::relative(file.path(), entry.path()).string());
    std::set<std::string> expected = {"ca.pem", identity + ".pem", identity + ".key"};
    if (client_principals().contains(identity)) expected.insert(identity + ".token");
    EXPECT_EQ(files, expected) << "bundles/" << identity;
    const CommandOutput verified =
        run_command("openssl verify -CAfile '" + (entry.path() / "ca.pem").string() + "' '" +
                    (entry.path() / (identity + ".pem")).string() + "' >/dev/null 2>&1");
    EXPECT_EQ(verified.exit_code, 0) << "bundles/" << identity << ": not signed by its ca.pem";
  }
  std::set<std::string> identities;
  for (const auto& [identity, classes] : identity_classes()) identities.insert(identity);
  EXPECT_EQ(bundles, identities);
  EXPECT_TRUE(std::filesystem::exists(dir_ / "ca.key")) << "the CA key stays where it signs";
}

TEST_F(DevCertificates, ThePolicyGivesEachIdentityItsClassesAndNoMore) {
  const YAML::Node policy = YAML::LoadFile((dir_ / "policy.json").string());
  std::map<std::string, std::set<std::string>> given;
  for (const auto& principal : policy["principals"]) {
    const auto name = principal["name"].as<std::string>();
    for (const auto& c : principal["classes"]) given[name].insert(c.as<std::string>());
    EXPECT_EQ(principal["cert_cn"].as<std::string>(""), name);
    EXPECT_FALSE(principal["cert_san"]) << name;
    // Servers authenticate by certificate only: no token to leak.
    EXPECT_EQ(static_cast<bool>(principal["token_sha256"]), client_principals().contains(name))
        << name;
  }
  EXPECT_EQ(given, identity_classes());
}

TEST_F(DevCertificates, EachServerCertificateIsValidForEveryNameItIsDialledBy) {
  std::map<std::string, std::set<std::string>> names;
  for (const std::string& identity : server_identities()) {
    const std::string described = describe(identity);
    names[identity] = alt_names(described);
    EXPECT_NE(described.find("CN = " + identity + "\n"), std::string::npos) << described;
    EXPECT_NE(described.find("TLS Web Server Authentication"), std::string::npos) << identity;
    EXPECT_NE(described.find("TLS Web Client Authentication"), std::string::npos) << identity;
    // Its own health check dials loopback.
    for (const char* loopback : {"localhost", "127.0.0.1"})
      EXPECT_TRUE(names[identity].contains(loopback)) << identity << " " << loopback;
  }
  for (const std::string& client : client_principals()) {
    const std::string described = describe(client);
    EXPECT_EQ(described.find("TLS Web Server Authentication"), std::string::npos) << client;
  }
  // Compose: a client dials the service by its name.
  const auto documents = load_all(kDeploy / "docker-compose.yml");
  int dialled = 0;
  for (const auto& entry : documents[0]["services"]) {
    std::vector<std::string> line;
    for (const auto& word : entry.second["command"]) line.push_back(word.as<std::string>());
    for (const auto& [f, target] : client_targets(line)) {
      const std::string host = host_of(target);
      const std::string identity = compose_identities().at(host);
      EXPECT_TRUE(names[identity].contains(host)) << identity << " is dialled as " << host;
      ++dialled;
    }
  }
  // Kubernetes: by the Service's name, also from another namespace.
  const Rendered rendered = kustomize(kDeploy / "k8s" / "overlays" / "single-node");
  ASSERT_EQ(rendered.exit_code, 0) << rendered.errors;
  auto objects = rendered.objects;
  for (const YAML::Node& job : load_all(kDeploy / "k8s" / "job-pipeline.yaml"))
    objects.push_back(job);
  for (const Workload& w : workloads(objects)) {
    for (const auto& c : w.pod_spec["containers"]) {
      for (const auto& [f, target] : client_targets(command_line(c))) {
        const std::string host = host_of(target);
        const std::string identity = workload_identities().at(host);
        for (const char* suffix : {"", ".pnp", ".pnp.svc", ".pnp.svc.cluster.local"})
          EXPECT_TRUE(names[identity].contains(host + suffix))
              << identity << " is dialled as " << host << suffix << " by " << w.name;
        ++dialled;
      }
    }
  }
  EXPECT_GT(dialled, 20);
}

}  // namespace
}  // namespace pnp::deploy_test
