#include "services/store/store_connections.h"

namespace pnp::services {

StoreConnections::StoreConnections(std::string path, store::DatabaseOptions options,
                                   store::StoreQuotas quotas)
    : path_(std::move(path)), options_(options), quotas_(quotas) {
  idle_.push_back(std::make_unique<store::RunStore>(path_, options_, quotas_));
}

StoreConnections::Borrowed::~Borrowed() {
  if (!store_) return;  // moved from
  std::lock_guard lock(owner_->mutex_);
  if (owner_->idle_.size() < kMaxIdle) owner_->idle_.push_back(std::move(store_));
}

StoreConnections::Borrowed StoreConnections::borrow() {
  {
    std::lock_guard lock(mutex_);
    if (!idle_.empty()) {
      auto store = std::move(idle_.back());
      idle_.pop_back();
      return Borrowed(*this, std::move(store));
    }
  }
  return Borrowed(*this, std::make_unique<store::RunStore>(path_, options_, quotas_));
}

}  // namespace pnp::services
