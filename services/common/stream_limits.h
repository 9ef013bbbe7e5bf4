#pragma once
// What one server's streaming calls may hold (docs/RELIABILITY.md, "Who may do what"): at
// most `max_streams` open at once, and at most a share of them for any one authenticated
// principal, so that a reader's watches cannot take the slots a trainer or the gateway
// needs (beyond either a new one ends RESOURCE_EXHAUSTED naming the flag); and a stream that
// carries no message either way for `idle_timeout` is cancelled, so a client that opens streams and
// walks away cannot hold a server's threads. Each streaming handler admits itself and marks its
// traffic:
//
//   auto slot = limits.admit(*context, "PredictSession");   // throws RESOURCE_EXHAUSTED
//   while (stream->Read(&request)) { slot.touch(); ... }
//
// A background thread cancels idle streams; cancelling is the only way to end a blocked
// synchronous Read from outside the handler. No stream is exempt: a watch the server feeds
// (a queued run's progress, the promotions) may rightly have nothing to say for long, so it
// sends a heartbeat every `heartbeat_interval()` of quiet, and only a heartbeat the transport
// took renews it. A client that stops reading fills its flow-control window, the writes block,
// and the watch is closed like any idle stream.

#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>

namespace pnp::services {

struct StreamLimitOptions {
  int max_streams = 256;
  // Per authenticated principal (under an auth policy); 0: a quarter of max_streams, at
  // least 1. Callers without a policy are not told apart.
  int max_streams_per_principal = 0;
  std::chrono::milliseconds idle_timeout = std::chrono::minutes(5);

  int principal_share() const {
    return max_streams_per_principal > 0 ? max_streams_per_principal : std::max(1, max_streams / 4);
  }
};

class StreamLimits {
 public:
  using Clock = std::chrono::steady_clock;

  // `service` names the server in the log line of each stream closed for idleness.
  StreamLimits(StreamLimitOptions options, std::string service);
  ~StreamLimits();
  StreamLimits(const StreamLimits&) = delete;
  StreamLimits& operator=(const StreamLimits&) = delete;

  // One admitted stream; released when destroyed.
  class Slot {
   public:
    static Slot none() { return Slot(nullptr, 0); }  // no limits: does nothing
    Slot(Slot&& other) noexcept : owner_(other.owner_), id_(other.id_) { other.owner_ = nullptr; }
    Slot(const Slot&) = delete;
    Slot& operator=(const Slot&) = delete;
    Slot& operator=(Slot&&) = delete;
    ~Slot();
    void touch();  // a message went one way or the other: not idle
    // How long a server-fed watch may stay quiet before it sends a heartbeat: a third of the
    // idle timeout, so that two may be late before the stream counts as idle.
    std::chrono::milliseconds heartbeat_interval() const;

   private:
    friend class StreamLimits;
    Slot(StreamLimits* owner, std::uint64_t id) : owner_(owner), id_(id) {}
    StreamLimits* owner_;
    std::uint64_t id_;
  };

  // Throws pnp::Error RESOURCE_EXHAUSTED when max_streams are open, or the caller's
  // principal holds its share.
  Slot admit(grpc::ServerContext& context, std::string_view rpc);

  int open_streams() const;
  std::uint64_t closed_for_idleness() const;
  const StreamLimitOptions& options() const { return options_; }

 private:
  struct Entry {
    grpc::ServerContext* context;
    std::string rpc;
    std::string principal;  // empty: no auth policy
    Clock::time_point last_activity;
    bool cancelled = false;
  };
  void reap_loop(const std::stop_token& stop);

  StreamLimitOptions options_;
  std::string service_;
  mutable std::mutex mutex_;
  std::condition_variable_any wake_;
  std::map<std::uint64_t, Entry> open_;
  std::uint64_t next_id_ = 1;
  std::uint64_t closed_idle_ = 0;
  std::jthread reaper_;  // last: stopped before the members it uses go
};

// `limits` may be null (a service built without limits, as in tests): Slot::none().
StreamLimits::Slot admit_stream(StreamLimits* limits, grpc::ServerContext& context,
                                std::string_view rpc);

}  // namespace pnp::services
