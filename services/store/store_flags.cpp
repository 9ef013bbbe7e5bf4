#include "services/store/store_flags.h"

#include "services/common/security_flags.h"

namespace pnp::services {

void add_remote_store_flags(CLI::App& app, RemoteStoreFlags& flags, CLI::Option* db_option) {
  auto* store =
      app.add_option("--store", flags.address,
                     "host:port of pnp-store-server, instead of opening a --db file here");
  if (db_option != nullptr) store->excludes(db_option);
  add_client_security_flags(app, flags.tls, "store-");
}

}  // namespace pnp::services
