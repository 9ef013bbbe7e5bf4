#include "services/common/server_runtime.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <thread>

#include "common/error.h"
#include "services/common/rpc_metrics.h"

namespace pnp::services {

ServerRuntime::ServerRuntime(const ServerConfig& config) : names_(config.service_names) {
  if (config.metrics == nullptr && !config.metrics_address.empty())
    throw_invalid_argument("metrics", "a registry to serve on " + config.metrics_address, "none");
  // Before gRPC starts: a metrics port that cannot listen fails the server whole.
  if (!config.metrics_address.empty())
    metrics_http_ = std::make_unique<MetricsHttpServer>(config.metrics_address, *config.metrics);
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  builder.AddListeningPort(config.address, grpc::InsecureServerCredentials(), &port_);
  builder.SetMaxReceiveMessageSize(config.max_message_bytes);
  builder.SetMaxSendMessageSize(config.max_message_bytes);
  for (grpc::Service* s : config.services) builder.RegisterService(s);
  if (config.metrics != nullptr) {
    std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> creators;
    creators.push_back(make_rpc_metrics_factory(*config.metrics));
    builder.experimental().SetInterceptorCreators(std::move(creators));
  }
  server_ = builder.BuildAndStart();
  if (!server_ || port_ == 0) {
    throw Error(ErrorCode::kUnavailable, "cannot listen on " + config.address);
  }
  set_serving(true);
}

void ServerRuntime::set_serving(bool serving) {
  auto* health = server_->GetHealthCheckService();
  if (!health) return;
  health->SetServingStatus(serving);
  for (const auto& name : names_) health->SetServingStatus(name, serving);
}

void ServerRuntime::shutdown(std::chrono::milliseconds grace) {
  set_serving(false);
  server_->Shutdown(std::chrono::system_clock::now() + grace);
  server_->Wait();
}

void block_termination_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

int wait_for_termination_signal() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  int signal = 0;
  sigwait(&set, &signal);
  return signal;
}

int serve_until_terminated(ServerRuntime& runtime, std::string_view service,
                           const std::function<void()>& periodic, std::chrono::milliseconds period,
                           const nlohmann::json& fields) {
  nlohmann::json listening = fields;
  listening["port"] = runtime.port();
  if (runtime.metrics_port() != 0) listening["metrics_port"] = runtime.metrics_port();
  log_event(service, "listening", listening);
  std::printf("%d\n", runtime.port());
  std::fflush(stdout);
  {
    std::jthread background([&](std::stop_token stop) {
      while (!stop.stop_requested()) {
        std::this_thread::sleep_for(period);
        periodic();
      }
    });
    const int signal = wait_for_termination_signal();
    log_event(service, "draining", {{"signal", signal}});
  }
  runtime.shutdown(std::chrono::seconds(5));
  log_event(service, "stopped");
  return 0;
}

void log_event(std::string_view service, std::string_view event, const nlohmann::json& fields) {
  nlohmann::json line = {{"ts_ms", std::chrono::duration_cast<std::chrono::milliseconds>(
                                       std::chrono::system_clock::now().time_since_epoch())
                                       .count()},
                         {"service", service},
                         {"event", event}};
  for (const auto& [key, value] : fields.items()) line[key] = value;
  // One stdio call per line: glibc locks the stream per call, so lines never interleave.
  const std::string text = line.dump() + "\n";
  std::fputs(text.c_str(), stderr);
}

}  // namespace pnp::services
