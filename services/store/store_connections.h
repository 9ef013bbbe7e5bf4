#pragma once
// The store service's SQLite connections: a RunStore serves one thread at a time, and the
// service's handlers run on many. A handler borrows an idle connection (opening one when
// none is idle) and gives it back when done; SQLite's WAL lets them read while one writes,
// and a busy writer waits (store/retry.h).

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "store/run_store.h"

namespace pnp::services {

class StoreConnections {
 public:
  // Opens (creating and migrating it if needed) the database once, here, so a bad path
  // fails at start, not at the first call.
  StoreConnections(std::string path, store::DatabaseOptions options,
                   store::StoreQuotas quotas = {});

  class Borrowed {
   public:
    Borrowed(StoreConnections& owner, std::unique_ptr<store::RunStore> store)
        : owner_(&owner), store_(std::move(store)) {}
    ~Borrowed();
    Borrowed(Borrowed&&) = default;
    Borrowed& operator=(Borrowed&&) = delete;
    Borrowed(const Borrowed&) = delete;
    Borrowed& operator=(const Borrowed&) = delete;
    store::RunStore& operator*() const { return *store_; }
    store::RunStore* operator->() const { return store_.get(); }

   private:
    StoreConnections* owner_;
    std::unique_ptr<store::RunStore> store_;
  };

  Borrowed borrow();
  const std::string& path() const { return path_; }

 private:
  static constexpr std::size_t kMaxIdle = 16;
  std::string path_;
  store::DatabaseOptions options_;
  store::StoreQuotas quotas_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<store::RunStore>> idle_;
};

}  // namespace pnp::services
