#include "services/inference/promotion_watcher.h"

#include "services/common/status.h"
#include "store/retry.h"

namespace pnp::services {

PromotionWatcher::PromotionWatcher(std::unique_ptr<RemoteStore> store,
                                   std::function<void()> on_change,
                                   std::function<void(const std::string&)> log,
                                   std::chrono::milliseconds retry)
    : store_(std::move(store)),
      on_change_(std::move(on_change)),
      log_(std::move(log)),
      retry_(retry),
      thread_([this](const std::stop_token& stop) { run(stop); }) {}

PromotionWatcher::~PromotionWatcher() {
  thread_.request_stop();
  std::lock_guard lock(mutex_);
  if (active_) active_->TryCancel();
}  // then the thread is joined

void PromotionWatcher::run(const std::stop_token& stop) {
  while (!stop.stop_requested()) {
    grpc::ClientContext context;
    {
      std::lock_guard lock(mutex_);
      if (stop.stop_requested()) return;
      active_ = &context;
    }
    const grpc::Status status =
        store_->watch_promotions(context, [&](const std::vector<store::Promotion>&) {
          on_change_();
          return !stop.stop_requested();
        });
    {
      std::lock_guard lock(mutex_);
      active_ = nullptr;
    }
    if (stop.stop_requested()) return;
    log_("watching the store's promotions (" + store_->address() + "): " +
         (status.ok() ? std::string("the stream ended")
                      : std::string(status_code_name(status.error_code())) + ": " +
                            status.error_message()) +
         "; reopening");
    store::sleep_unless_stopped(retry_, stop);
  }
}

}  // namespace pnp::services
