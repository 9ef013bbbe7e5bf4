#pragma once
// The flags of a program that may reach the store through pnp-store-server instead of
// opening a --db file itself: --store host:port and how to dial it (--store-tls-ca,
// --store-tls-cert/--store-tls-key, --store-token-file).

#include <CLI/CLI.hpp>
#include <string>

#include "services/common/transport_security.h"

namespace pnp::services {

struct RemoteStoreFlags {
  std::string address;  // empty: the program opens its --db file
  ClientTlsFiles tls;
  bool remote() const { return !address.empty(); }
};

// Adds --store (which excludes `db_option`, the program's --db) and the --store-tls-* flags.
void add_remote_store_flags(CLI::App& app, RemoteStoreFlags& flags, CLI::Option* db_option);

}  // namespace pnp::services
