#include "services/common/rpc_metrics.h"

#include <grpcpp/generic/async_generic_service.h>

#include <array>
#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <string>
#include <unordered_map>

#include "common/handover.h"
#include "services/common/status.h"

namespace pnp::services {
namespace {

namespace gx = grpc::experimental;

constexpr std::string_view kRequests = "pnp_rpc_requests_total";
constexpr std::string_view kRequestsHelp = "RPCs finished, by full method name and status code.";
constexpr std::string_view kDuration = "pnp_rpc_duration_seconds";
constexpr std::string_view kDurationHelp =
    "RPC duration from the call's arrival to its final status, in seconds.";
constexpr std::string_view kInFlight = "pnp_rpc_in_flight";
constexpr std::string_view kInFlightHelp = "RPCs started and not yet finished.";
constexpr std::string_view kUnregistered = "unregistered";
constexpr int kCodes = grpc::StatusCode::UNAUTHENTICATED + 1;  // OK = 0 ... 16

const std::vector<double>& duration_bounds() {
  static const std::vector<double> bounds = {50e-6, 100e-6, 250e-6, 500e-6, 1e-3, 2.5e-3,
                                             5e-3,  10e-3,  25e-3,  50e-3,  0.1,  0.25,
                                             0.5,   1,      2.5,    5,      10};
  return bounds;
}

int code_index(grpc::StatusCode code) {
  return code >= 0 && code < kCodes ? code : grpc::StatusCode::UNKNOWN;
}

// One method's series. Each code's counter and histogram are looked up in the registry on
// first use and cached here, so a finishing call touches only atomics.
class MethodMetrics {
 public:
  MethodMetrics(MetricsRegistry& registry, std::string method)
      : registry_(registry),
        method_(std::move(method)),
        in_flight_(registry.gauge(kInFlight, kInFlightHelp, {{"method", method_}})) {}

  Gauge& in_flight() { return in_flight_; }

  void finish(grpc::StatusCode status, double seconds) {
    const int code = code_index(status);
    auto& slot = slots_[static_cast<std::size_t>(code)];
    Counter* requests = slot.requests.load(std::memory_order_acquire);
    Histogram* duration = slot.duration.load(std::memory_order_acquire);
    if (requests == nullptr || duration == nullptr) {
      // Racing first calls find the same metrics: the registry returns one per label set.
      const Labels labels = {{"method", method_},
                             {"code", std::string(status_code_name(grpc::StatusCode(code)))}};
      requests = &registry_.counter(kRequests, kRequestsHelp, labels);
      duration = &registry_.histogram(kDuration, kDurationHelp, duration_bounds(), labels);
      slot.requests.store(requests, std::memory_order_release);
      slot.duration.store(duration, std::memory_order_release);
    }
    requests->inc();
    duration->observe(seconds);
  }

 private:
  struct Slot {
    std::atomic<Counter*> requests{nullptr};
    std::atomic<Histogram*> duration{nullptr};
  };
  MetricsRegistry& registry_;
  std::string method_;
  Gauge& in_flight_;
  std::array<Slot, kCodes> slots_;
};

// Lives as long as its call (gRPC owns it). A call is recorded when the server sends its
// status, which happens once however many messages a stream carries, and before the
// client can see the status; a call that ends without one is recorded as CANCELLED.
class RpcMetricsInterceptor final : public gx::Interceptor {
 public:
  explicit RpcMetricsInterceptor(MethodMetrics& metrics)
      : metrics_(metrics), start_(std::chrono::steady_clock::now()) {
    metrics_.in_flight().inc();
  }
  ~RpcMetricsInterceptor() override {
    receive_handover(&handed_over_);  // the body runs before handed_over_ is destroyed
    finish(grpc::StatusCode::CANCELLED);
  }

  void Intercept(gx::InterceptorBatchMethods* methods) override {
    {
      const HandoverScope handover(handed_over_);
      if (methods->QueryInterceptionHookPoint(gx::InterceptionHookPoints::PRE_SEND_STATUS))
        finish(methods->GetSendStatus().error_code());
    }
    methods->Proceed();  // last: the call may end, and this be destroyed, from here on
  }

 private:
  void finish(grpc::StatusCode code) {
    if (finished_.exchange(true)) return;
    metrics_.in_flight().dec();
    metrics_.finish(
        code, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
  }

  MethodMetrics& metrics_;
  std::chrono::steady_clock::time_point start_;
  std::atomic<bool> finished_{false};  // a stream's hooks may run on several threads
  HandedOver handed_over_;             // last: gRPC calls and destroys it on its own threads
};

struct StringHash {
  using is_transparent = void;
  std::size_t operator()(std::string_view s) const { return std::hash<std::string_view>{}(s); }
};

class RpcMetricsFactory final : public gx::ServerInterceptorFactoryInterface {
 public:
  explicit RpcMetricsFactory(MetricsRegistry& registry) : registry_(registry) {}

  gx::Interceptor* CreateServerInterceptor(gx::ServerRpcInfo* info) override {
    // gRPC answers methods no service registered through a generic service (callback or
    // async, depending on the server's other services), with the method name the client
    // sent: those share one label value. The runtime registers no generic service itself.
    const grpc::ServerContextBase* context = info->server_context();
    const bool registered =
        dynamic_cast<const grpc::GenericCallbackServerContext*>(context) == nullptr &&
        dynamic_cast<const grpc::GenericServerContext*>(context) == nullptr;
    const std::string_view method =
        registered && info->method() != nullptr ? info->method() : kUnregistered;
    // gRPC takes ownership of the interceptor.
    return std::make_unique<RpcMetricsInterceptor>(metrics_for(method)).release();
  }

 private:
  MethodMetrics& metrics_for(std::string_view method) {
    std::lock_guard lock(mutex_);
    auto it = methods_.find(method);
    if (it == methods_.end())
      it = methods_
               .emplace(std::string(method),
                        std::make_unique<MethodMetrics>(registry_, std::string(method)))
               .first;
    return *it->second;
  }

  MetricsRegistry& registry_;
  std::mutex mutex_;
  std::unordered_map<std::string, std::unique_ptr<MethodMetrics>, StringHash, std::equal_to<>>
      methods_;
};

}  // namespace

std::unique_ptr<gx::ServerInterceptorFactoryInterface> make_rpc_metrics_factory(
    MetricsRegistry& registry) {
  return std::make_unique<RpcMetricsFactory>(registry);
}

}  // namespace pnp::services
