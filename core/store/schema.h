#pragma once
// The store's schema as an ordered list of migrations. PRAGMA user_version records how
// many have run; opening a database runs the missing ones, all in one transaction,
// and refuses a database written by a newer version of the code.

#include "store/sqlite.h"

namespace pnp::store {

int schema_version();  // the number of migrations this code knows
void migrate(Database& db);
// Runs the migrations up to `target` only: how a test builds a database of an older build.
void migrate_to(Database& db, int target);

}  // namespace pnp::store
