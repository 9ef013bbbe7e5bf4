#pragma once
// Which SQLite store a server opens. A store is never created by accident: a server run
// without --db and without $PNP_DB is refused (before, it silently made ./pnp.db), and a
// server that only reads (inference) refuses a file that does not exist unless asked to
// start an empty one.

#include <string>

namespace pnp::services {

// `flag`: the --db value ("" when not given). Returns the path to open, or throws
// INVALID_ARGUMENT naming --db and what was expected.
std::string resolve_store_path(const std::string& flag, bool must_exist);

}  // namespace pnp::services
