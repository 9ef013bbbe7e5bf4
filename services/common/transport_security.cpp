#include "services/common/transport_security.h"

#include <grpcpp/security/tls_certificate_provider.h>
#include <grpcpp/security/tls_credentials_options.h>

#include <fstream>
#include <sstream>

#include "common/error.h"
#include "common/handover.h"
#include "services/common/address.h"

namespace pnp::services {
namespace {

std::string read_file(const std::string& path, std::string_view flag) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw_invalid_argument(flag, "a readable file", "\"" + path + "\" (cannot be opened)");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// A PEM file with at least one block of `kind` ("CERTIFICATE", "PRIVATE KEY"...).
void require_pem(const std::string& path, std::string_view flag, std::string_view kind) {
  const std::string text = read_file(path, flag);
  if (text.find("-----BEGIN ") == std::string::npos ||
      text.find(std::string(kind) + "-----") == std::string::npos) {
    throw_invalid_argument(flag, "a PEM file with a " + std::string(kind),
                           "\"" + path + "\" (no such block)");
  }
}

// Sends `authorization: Bearer <token>` with every call on the channel.
class BearerToken final : public grpc::MetadataCredentialsPlugin {
 public:
  explicit BearerToken(std::string token) : header_("Bearer " + std::move(token)) {}
  bool IsBlocking() const override { return false; }
  const char* GetType() const override { return "pnp-bearer"; }
  grpc::Status GetMetadata(grpc::string_ref, grpc::string_ref, const grpc::AuthContext&,
                           std::multimap<grpc::string, grpc::string>* metadata) override {
    const HandoverScope handover(handed_over_);
    metadata->emplace("authorization", header_);
    return grpc::Status::OK;
  }
  grpc::string DebugString() override { return "BearerToken"; }  // never the token

 private:
  std::string header_;
  HandedOver handed_over_;  // last: gRPC calls and destroys it on its own threads
};

// A certificate without its key, or a key without its certificate.
void require_whole_pair(const std::string& cert, const std::string& key) {
  if (cert.empty() == key.empty()) return;
  throw_invalid_argument(
      cert.empty() ? "--tls-cert" : "--tls-key",
      "given together with " + std::string(cert.empty() ? "--tls-key" : "--tls-cert"),
      "only one of them");
}

}  // namespace

void validate(const ServerTlsFiles& files) {
  require_whole_pair(files.cert, files.key);
  if (!files.enabled()) {
    if (!files.client_ca.empty())
      throw_invalid_argument("--tls-client-ca", "only with --tls-cert and --tls-key", "without");
    return;
  }
  require_pem(files.cert, "--tls-cert", "CERTIFICATE");
  require_pem(files.key, "--tls-key", "PRIVATE KEY");
  if (!files.client_ca.empty()) require_pem(files.client_ca, "--tls-client-ca", "CERTIFICATE");
  if (files.reload_s < 1 || files.reload_s > 86'400)
    throw_invalid_argument("--tls-reload-s", "1 to 86400", std::to_string(files.reload_s));
}

void validate(const ClientTlsFiles& files) {
  require_whole_pair(files.cert, files.key);
  if (!files.enabled()) {
    if (!files.cert.empty())
      throw_invalid_argument("--tls-cert", "only with --tls-ca (mutual TLS)", "without");
    if (!files.token_file.empty()) {
      throw Error(ErrorCode::kFailedPrecondition,
                  "--token-file needs TLS (--tls-ca): a bearer token over plaintext would "
                  "cross the network readable");
    }
    return;
  }
  require_pem(files.ca, "--tls-ca", "CERTIFICATE");
  if (!files.cert.empty()) {
    require_pem(files.cert, "--tls-cert", "CERTIFICATE");
    require_pem(files.key, "--tls-key", "PRIVATE KEY");
  }
  if (!files.token_file.empty()) read_token_file(files.token_file, "--token-file");
}

std::shared_ptr<grpc::ServerCredentials> server_credentials(const ServerTlsFiles& files) {
  validate(files);
  if (!files.enabled()) return grpc::InsecureServerCredentials();
  auto provider = std::make_shared<grpc::experimental::FileWatcherCertificateProvider>(
      files.key, files.cert, files.client_ca, files.reload_s);
  grpc::experimental::TlsServerCredentialsOptions options(provider);
  options.watch_identity_key_cert_pairs();
  if (!files.client_ca.empty()) {
    options.watch_root_certs();
    options.set_cert_request_type(GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY);
  }
  return grpc::experimental::TlsServerCredentials(options);
}

std::shared_ptr<grpc::Channel> dial(const std::string& address, const ClientTlsFiles& files,
                                    grpc::ChannelArguments args) {
  validate_address(address, "address");
  validate(files);
  if (!files.enabled())
    return grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), args);
  grpc::SslCredentialsOptions ssl;
  ssl.pem_root_certs = read_file(files.ca, "--tls-ca");
  if (!files.cert.empty()) {
    ssl.pem_cert_chain = read_file(files.cert, "--tls-cert");
    ssl.pem_private_key = read_file(files.key, "--tls-key");
  }
  if (!files.server_name.empty()) args.SetSslTargetNameOverride(files.server_name);
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::SslCredentials(ssl);
  if (!files.token_file.empty()) {
    credentials = grpc::CompositeChannelCredentials(
        credentials, grpc::MetadataCredentialsFromPlugin(std::make_unique<BearerToken>(
                         read_token_file(files.token_file, "--token-file"))));
  }
  return grpc::CreateCustomChannel(address, credentials, args);
}

bool is_loopback_address(const std::string& address) {
  if (address.starts_with("unix:")) return true;
  const auto colon = address.rfind(':');
  std::string host = colon == std::string::npos ? address : address.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);
  return host == "localhost" || host == "::1" || host.starts_with("127.");
}

std::string read_token_file(const std::string& path, std::string_view flag) {
  std::ifstream in(path);
  if (!in) throw Error(ErrorCode::kNotFound, std::string(flag) + ": cannot read " + path);
  std::string token;
  std::getline(in, token);
  while (!token.empty() && (token.back() == '\r' || token.back() == ' ')) token.pop_back();
  if (token.empty())
    throw_invalid_argument(flag, "a file whose first line is the token", "an empty first line");
  return token;
}

}  // namespace pnp::services
