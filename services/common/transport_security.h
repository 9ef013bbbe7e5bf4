#pragma once
// How a server listens and a client dials: plaintext, TLS, or mutual TLS, from PEM files.
// A server re-reads its certificate, key and client CA when the files change (rotation
// without a restart; replace them atomically, e.g. by renaming a new file over the old).

#include <grpcpp/grpcpp.h>

#include <memory>
#include <string>

namespace pnp::services {

struct ServerTlsFiles {
  std::string cert;        // PEM certificate chain; empty: plaintext
  std::string key;         // PEM private key
  std::string client_ca;   // PEM CA bundle; set: clients must present a certificate it signed
  unsigned reload_s = 10;  // how often the files are checked for changes
  bool enabled() const { return !cert.empty(); }
};

struct ClientTlsFiles {
  std::string ca;    // PEM roots to verify the server; empty: plaintext
  std::string cert;  // PEM client certificate for mutual TLS (with key)
  std::string key;
  std::string server_name;  // the name to verify in the server's certificate, when dialling
                            // by another name (e.g. an IP)
  std::string token_file;   // a bearer token sent with every call (TLS only)
  bool enabled() const { return !ca.empty(); }
};

// INVALID_ARGUMENT naming the flag for missing or unreadable files or half a pair.
void validate(const ServerTlsFiles& files);
void validate(const ClientTlsFiles& files);

std::shared_ptr<grpc::ServerCredentials> server_credentials(const ServerTlsFiles& files);

// A channel to `address`, with the credentials and bearer token `files` name. A token is
// refused over plaintext (FAILED_PRECONDITION): it would cross the network readable.
std::shared_ptr<grpc::Channel> dial(const std::string& address, const ClientTlsFiles& files,
                                    grpc::ChannelArguments args = {});

// true for 127.0.0.0/8, ::1, localhost and unix: addresses.
bool is_loopback_address(const std::string& address);

// The first line of a file, without its line end (a token file); NOT_FOUND naming `flag`.
std::string read_token_file(const std::string& path, std::string_view flag);

}  // namespace pnp::services
