#pragma once
// The read side of a gRPC stream with a deadline. Synchronous gRPC reads block without
// one, and the gateway must notice within its dead-man timeout that an answer is late; so
// a reader thread moves every message into this mailbox and the loop waits on it with a
// deadline. gRPC allows one reader and one writer at a time: the loop keeps writing.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <thread>

namespace pnp::gateway {

template <typename Message>
class StreamMailbox {
 public:
  using Clock = std::chrono::steady_clock;

  // `read` is called on the reader thread until it returns false (the stream ended).
  template <typename Read>
  explicit StreamMailbox(Read read)
      : reader_([this, read]() mutable {
          Message message;
          while (read(message)) {
            std::lock_guard lock(mutex_);
            queue_.push_back(std::move(message));
            arrived_.notify_all();
          }
          std::lock_guard lock(mutex_);
          ended_ = true;
          arrived_.notify_all();
        }) {}
  // The stream must have been made to end (cancelled or finished) before this runs.
  ~StreamMailbox() = default;  // std::jthread joins
  StreamMailbox(const StreamMailbox&) = delete;
  StreamMailbox& operator=(const StreamMailbox&) = delete;

  // The next message, or nullopt when the deadline passes, the stream has ended or
  // `interrupted` (looked at every `poll`) is set.
  std::optional<Message> next(Clock::time_point deadline,
                              const std::atomic<bool>* interrupted = nullptr,
                              std::chrono::milliseconds poll = std::chrono::milliseconds(5)) {
    std::unique_lock lock(mutex_);
    const auto ready = [&] { return !queue_.empty() || ended_; };
    while (!ready() && Clock::now() < deadline && !(interrupted && interrupted->load())) {
      arrived_.wait_until(lock, std::min(deadline, Clock::now() + poll), ready);
    }
    if (queue_.empty()) return std::nullopt;
    Message message = std::move(queue_.front());
    queue_.pop_front();
    return message;
  }
  bool ended() const {
    std::lock_guard lock(mutex_);
    return ended_ && queue_.empty();
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::deque<Message> queue_;
  bool ended_ = false;
  std::jthread reader_;  // last: starts after the members it uses exist
};

}  // namespace pnp::gateway
