#include "services/common/stream_limits.h"

#include <algorithm>

#include "common/error.h"
#include "services/common/access_control.h"
#include "services/common/server_runtime.h"

namespace pnp::services {

StreamLimits::StreamLimits(StreamLimitOptions options, std::string service)
    : options_(options), service_(std::move(service)) {
  if (options_.max_streams < 1)
    throw_invalid_argument("--max-streams", "at least 1", std::to_string(options_.max_streams));
  if (options_.max_streams_per_principal < 0 ||
      options_.max_streams_per_principal > options_.max_streams) {
    throw_invalid_argument("--max-streams-per-principal",
                           "0 (a quarter of --max-streams) to --max-streams (" +
                               std::to_string(options_.max_streams) + ")",
                           std::to_string(options_.max_streams_per_principal));
  }
  if (options_.idle_timeout < std::chrono::milliseconds(1)) {
    throw_invalid_argument("--stream-idle-timeout-s", "a positive duration",
                           std::to_string(options_.idle_timeout.count()) + " ms");
  }
  reaper_ = std::jthread([this](std::stop_token stop) { reap_loop(stop); });
}

StreamLimits::~StreamLimits() {
  reaper_.request_stop();
  wake_.notify_all();
}

StreamLimits::Slot StreamLimits::admit(grpc::ServerContext& context, std::string_view rpc) {
  std::lock_guard lock(mutex_);
  if (static_cast<int>(open_.size()) >= options_.max_streams) {
    throw Error(ErrorCode::kResourceExhausted,
                std::string(rpc) + ": this server already holds its " +
                    std::to_string(options_.max_streams) +
                    " open streams (--max-streams); retry when one ends");
  }
  std::string principal = principal_of(context);
  if (!principal.empty()) {
    const auto held = std::count_if(open_.begin(), open_.end(),
                                    [&](const auto& e) { return e.second.principal == principal; });
    if (held >= options_.principal_share()) {
      throw Error(ErrorCode::kResourceExhausted,
                  std::string(rpc) + ": principal \"" + principal + "\" already holds its " +
                      std::to_string(options_.principal_share()) +
                      " open streams on this server (--max-streams-per-principal); retry when "
                      "one ends");
    }
  }
  const std::uint64_t id = next_id_++;
  open_.emplace(id, Entry{&context, std::string(rpc), std::move(principal), Clock::now()});
  return Slot(this, id);
}

StreamLimits::Slot::~Slot() {
  if (owner_ == nullptr) return;
  std::lock_guard lock(owner_->mutex_);
  owner_->open_.erase(id_);
}

void StreamLimits::Slot::touch() {
  if (owner_ == nullptr) return;
  const auto now = Clock::now();
  std::lock_guard lock(owner_->mutex_);
  const auto it = owner_->open_.find(id_);
  if (it != owner_->open_.end()) it->second.last_activity = now;
}

std::chrono::milliseconds StreamLimits::Slot::heartbeat_interval() const {
  // Without limits nothing closes a quiet watch; a heartbeat a minute still tells the
  // client that the server is there.
  if (owner_ == nullptr) return std::chrono::minutes(1);
  return std::max(owner_->options_.idle_timeout / 3, std::chrono::milliseconds(1));
}

int StreamLimits::open_streams() const {
  std::lock_guard lock(mutex_);
  return static_cast<int>(open_.size());
}

std::uint64_t StreamLimits::closed_for_idleness() const {
  std::lock_guard lock(mutex_);
  return closed_idle_;
}

void StreamLimits::reap_loop(const std::stop_token& stop) {
  // A quarter of the timeout between looks: a stream is closed within 1.25 timeouts.
  const auto period = std::clamp<std::chrono::milliseconds>(
      options_.idle_timeout / 4, std::chrono::milliseconds(10), std::chrono::seconds(5));
  std::unique_lock lock(mutex_);
  while (!stop.stop_requested()) {
    wake_.wait_for(lock, stop, period, [] { return false; });
    const auto now = Clock::now();
    for (auto& [id, entry] : open_) {
      if (entry.cancelled || now - entry.last_activity < options_.idle_timeout) continue;
      // Under the lock: the slot, and so its call, cannot end meanwhile.
      entry.context->TryCancel();
      entry.cancelled = true;
      ++closed_idle_;
      log_event(service_, "stream_idle_closed",
                {{"rpc", entry.rpc},
                 {"peer", entry.context->peer()},
                 {"idle_ms",
                  std::chrono::duration_cast<std::chrono::milliseconds>(now - entry.last_activity)
                      .count()}});
    }
  }
}

StreamLimits::Slot admit_stream(StreamLimits* limits, grpc::ServerContext& context,
                                std::string_view rpc) {
  return limits ? limits->admit(context, rpc) : StreamLimits::Slot::none();
}

}  // namespace pnp::services
