#pragma once
// Keeps an inference server on a remote store (pnp-store-server) serving what is promoted:
// it holds a WatchPromotions stream open and calls `on_change` whenever the promotions
// change (and once when the stream is first opened), instead of polling the store. A
// stream that breaks (the store server restarted) is reopened after `retry`; each reopen
// calls `on_change` again, so a change made while the stream was down is not missed.

#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "services/store/remote_store.h"

namespace pnp::services {

class PromotionWatcher {
 public:
  // `log(event, error)` reports a broken stream; `on_change` runs on the watcher's thread.
  PromotionWatcher(std::unique_ptr<RemoteStore> store, std::function<void()> on_change,
                   std::function<void(const std::string&)> log,
                   std::chrono::milliseconds retry = std::chrono::seconds(1));
  ~PromotionWatcher();  // cancels the stream and joins
  PromotionWatcher(const PromotionWatcher&) = delete;
  PromotionWatcher& operator=(const PromotionWatcher&) = delete;

 private:
  void run(const std::stop_token& stop);

  std::unique_ptr<RemoteStore> store_;
  std::function<void()> on_change_;
  std::function<void(const std::string&)> log_;
  std::chrono::milliseconds retry_;
  std::mutex mutex_;
  grpc::ClientContext* active_ = nullptr;  // the open stream's, guarded by mutex_
  std::jthread thread_;                    // last: joined before the members it uses go
};

}  // namespace pnp::services
