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

namespace pnp::services {
namespace {

namespace gx = grpc::experimental;

// The names and labels of go-grpc-prometheus, which Grafana's gRPC dashboards and most
// alert rules expect.
constexpr std::string_view kStarted = "grpc_server_started_total";
constexpr std::string_view kStartedHelp = "Total number of RPCs started on the server.";
constexpr std::string_view kHandled = "grpc_server_handled_total";
constexpr std::string_view kHandledHelp =
    "Total number of RPCs completed on the server, regardless of success or failure.";
constexpr std::string_view kHandling = "grpc_server_handling_seconds";
constexpr std::string_view kHandlingHelp =
    "Histogram of response latency (seconds) of gRPC that had been application-level handled "
    "by the server.";
constexpr std::string_view kUnregistered = "unregistered";
constexpr int kCodes = grpc::StatusCode::UNAUTHENTICATED + 1;  // OK = 0 ... 16

// Go's codes.Code names, as go-grpc-prometheus writes grpc_code.
constexpr std::array<std::string_view, kCodes> kGoCodeNames = {
    "OK",       "Canceled",       "Unknown",          "InvalidArgument",   "DeadlineExceeded",
    "NotFound", "AlreadyExists",  "PermissionDenied", "ResourceExhausted", "FailedPrecondition",
    "Aborted",  "OutOfRange",     "Unimplemented",    "Internal",          "Unavailable",
    "DataLoss", "Unauthenticated"};

// 50 us to 10 s; 2 ms is a bound so that an alert on a 2 ms p99 reads an exact bucket.
const std::vector<double>& handling_bounds() {
  static const std::vector<double> bounds = {50e-6,  100e-6, 250e-6, 500e-6, 1e-3,  2e-3,
                                             2.5e-3, 5e-3,   10e-3,  25e-3,  50e-3, 0.1,
                                             0.25,   0.5,    1,      2.5,    5,     10};
  return bounds;
}

int code_index(grpc::StatusCode code) {
  return code >= 0 && code < kCodes ? code : grpc::StatusCode::UNKNOWN;
}

std::string_view type_label(gx::ServerRpcInfo::Type type) {
  switch (type) {
    case gx::ServerRpcInfo::Type::UNARY:
      return "unary";
    case gx::ServerRpcInfo::Type::CLIENT_STREAMING:
      return "client_stream";
    case gx::ServerRpcInfo::Type::SERVER_STREAMING:
      return "server_stream";
    case gx::ServerRpcInfo::Type::BIDI_STREAMING:
      return "bidi_stream";
  }
  return "unary";
}

// One method's series. Each code's counter is looked up in the registry on first use and
// cached here, so a finishing call touches only atomics and its histogram.
class MethodMetrics {
 public:
  // `full_method`: "/package.Service/Method", or "unregistered".
  MethodMetrics(MetricsRegistry& registry, std::string_view full_method,
                gx::ServerRpcInfo::Type type)
      : registry_(registry),
        labels_(method_labels(full_method, type)),
        started_(registry.counter(kStarted, kStartedHelp, labels_)),
        handling_(registry.histogram(kHandling, kHandlingHelp, handling_bounds(), labels_)) {}

  void start() { started_.Increment(); }

  void finish(grpc::StatusCode status, double seconds) {
    const int code = code_index(status);
    auto& slot = handled_[static_cast<std::size_t>(code)];
    Counter* handled = slot.load(std::memory_order_acquire);
    if (handled == nullptr) {
      // Racing first calls find the same counter: the registry returns one per label set.
      Labels labels = labels_;
      labels.emplace_back("grpc_code", kGoCodeNames[static_cast<std::size_t>(code)]);
      handled = &registry_.counter(kHandled, kHandledHelp, labels);
      slot.store(handled, std::memory_order_release);
    }
    handled->Increment();
    handling_.Observe(seconds);
  }

 private:
  static Labels method_labels(std::string_view full_method, gx::ServerRpcInfo::Type type) {
    std::string_view service = kUnregistered, method = kUnregistered;
    if (const auto slash = full_method.rfind('/');
        full_method.starts_with('/') && slash != std::string_view::npos && slash > 0) {
      service = full_method.substr(1, slash - 1);
      method = full_method.substr(slash + 1);
    }
    return {{"grpc_type", std::string(type_label(type))},
            {"grpc_service", std::string(service)},
            {"grpc_method", std::string(method)}};
  }

  MetricsRegistry& registry_;
  Labels labels_;
  Counter& started_;
  Histogram& handling_;
  std::array<std::atomic<Counter*>, kCodes> handled_{};
};

// Lives as long as its call (gRPC owns it). A call is recorded when the server sends its
// status, which happens once however many messages a stream carries, and before the
// client can see the status; a call that ends without one is recorded as CANCELLED.
class RpcMetricsInterceptor final : public gx::Interceptor {
 public:
  explicit RpcMetricsInterceptor(MethodMetrics& metrics)
      : metrics_(metrics), start_(std::chrono::steady_clock::now()) {
    metrics_.start();
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
    return std::make_unique<RpcMetricsInterceptor>(metrics_for(method, info->type())).release();
  }

 private:
  MethodMetrics& metrics_for(std::string_view method, gx::ServerRpcInfo::Type type) {
    // An unregistered call's type is gRPC's guess (bidi): the label set stays one.
    const auto key = std::string(method);
    std::lock_guard lock(mutex_);
    auto it = methods_.find(key);
    if (it == methods_.end())
      it = methods_.emplace(key, std::make_unique<MethodMetrics>(registry_, method, type)).first;
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
