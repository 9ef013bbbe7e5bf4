#include "services/common/server_runtime.h"

#include <fcntl.h>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <mutex>
#include <thread>

#include "common/error.h"
#include "services/common/access_control.h"
#include "services/common/address.h"
#include "services/common/rpc_metrics.h"
#include "services/common/server_memory.h"

namespace pnp::services {

void check_exposure(const std::string& address, const std::string& metrics_address,
                    const ServerSecurity& security) {
  if (security.policy && !security.tls.enabled()) {
    throw Error(ErrorCode::kFailedPrecondition,
                "--auth-policy needs TLS (--tls-cert and --tls-key): tokens and principals "
                "mean nothing over plaintext");
  }
  if (security.insecure) return;
  if (!is_loopback_address(address)) {
    if (!security.tls.enabled()) {
      throw Error(ErrorCode::kFailedPrecondition,
                  "--address " + address +
                      " is reachable beyond this machine: serve TLS (--tls-cert, --tls-key, "
                      "and --tls-client-ca or --auth-policy) or pass --insecure");
    }
    // TLS alone encrypts; it does not say who calls. Every server changes state (and one
    // moves the arm): beyond loopback a caller must authenticate.
    if (security.tls.client_ca.empty() && !security.policy) {
      throw Error(ErrorCode::kFailedPrecondition,
                  "--address " + address +
                      " is reachable beyond this machine and TLS without --tls-client-ca or "
                      "--auth-policy lets anyone call: require client certificates "
                      "(--tls-client-ca) or tokens (--auth-policy), or pass --insecure");
    }
  }
  if (!metrics_address.empty() && !is_loopback_address(metrics_address) &&
      !security.public_metrics) {
    throw Error(ErrorCode::kFailedPrecondition,
                "--metrics-address " + metrics_address +
                    " is plaintext HTTP reachable beyond this machine: bind it to loopback, or "
                    "pass --public-metrics (its counters are public to the network)");
  }
}

ServerRuntime::ServerRuntime(const ServerConfig& config) : names_(config.service_names) {
  keep_large_blocks_mapped();  // before the server's threads allocate
  validate_address(config.address, "--address");
  if (!config.metrics_address.empty())
    validate_address(config.metrics_address, "--metrics-address");
  check_exposure(config.address, config.metrics_address, config.security);
  if (config.security.insecure &&
      (!is_loopback_address(config.address) || !config.security.tls.enabled())) {
    log_event(config.log_name, "insecure",
              {{"address", config.address},
               {"tls", config.security.tls.enabled()},
               {"warning", "--insecure: plaintext is allowed beyond loopback"}});
  }
  auto credentials = server_credentials(config.security.tls);
  if (config.security.policy)
    credentials->SetAuthMetadataProcessor(
        make_policy_processor(config.security.policy, config.log_name, config.security.audit));
  if (config.metrics == nullptr && !config.metrics_address.empty())
    throw_invalid_argument("metrics", "a registry to serve on " + config.metrics_address, "none");
  // Before gRPC starts: a metrics port that cannot listen fails the server whole.
  if (!config.metrics_address.empty())
    metrics_http_ = std::make_unique<MetricsHttpServer>(config.metrics_address, *config.metrics);
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  builder.AddListeningPort(config.address, credentials, &port_);
  // Off: with SO_REUSEPORT a second server on a port in use binds too, and the kernel then
  // spreads the clients over two servers (two stores, two policies).
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  // Connections whose client vanished (no TCP reset) are found by keepalive pings and
  // closed with their streams; clients may ping at most every 10 s without data, two
  // strikes; a connection with no call for 30 min is closed.
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, 60'000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 20'000);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS, 10'000);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MAX_PING_STRIKES, 2);
  builder.AddChannelArgument(GRPC_ARG_MAX_CONNECTION_IDLE_MS, 30 * 60'000);
  builder.AddChannelArgument(GRPC_ARG_MAX_CONCURRENT_STREAMS, kMaxStreamsPerConnection);
  builder.SetMaxReceiveMessageSize(config.max_message_bytes);
  builder.SetMaxSendMessageSize(config.max_message_bytes);
  for (grpc::Service* s : config.services) builder.RegisterService(s);
  std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> creators;
  if (config.metrics != nullptr) creators.push_back(make_rpc_metrics_factory(*config.metrics));
  creators.push_back(make_audit_factory(config.log_name, config.security.audit));
  builder.experimental().SetInterceptorCreators(std::move(creators));
  server_ = builder.BuildAndStart();
  if (!server_ || port_ == 0) {
    const std::string reason = listen_failure_reason(config.address);
    throw Error(ErrorCode::kUnavailable,
                "cannot listen on " + config.address + (reason.empty() ? "" : ": " + reason));
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

namespace {

// The write end of the self-pipe the signal handler reports to. Process-wide by nature (a
// signal handler cannot be handed state); written once by catch_termination_signals.
int signal_pipe_write_fd = -1;

void on_termination_signal(int signal) {
  const auto byte = static_cast<unsigned char>(signal);
  [[maybe_unused]] const auto written = ::write(signal_pipe_write_fd, &byte, 1);
}

int signal_pipe_read_fd = -1;

}  // namespace

// A handler, not a blocked mask: threads started before main (OpenBLAS starts its pool
// from a static constructor) never block anything, and a signal delivered to one of them
// would otherwise take the default action and kill the server mid-drain.
void catch_termination_signals() {
  if (signal_pipe_write_fd >= 0) return;
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) throw_internal("cannot create the signal pipe");
  signal_pipe_read_fd = fds[0];
  signal_pipe_write_fd = fds[1];
  struct sigaction action {};
  action.sa_handler = on_termination_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGINT, &action, nullptr);
}

// Parks in poll, not in read: ThreadSanitizer runs a signal handler at once only on a
// thread parked in a call it knows may block (poll is one, read is not); elsewhere it defers
// the handler to the thread's next intercepted call, and a thread asleep in read for the
// very byte the handler writes would wait forever.
int wait_for_termination_signal() {
  if (signal_pipe_read_fd < 0) throw_internal("catch_termination_signals() was not called");
  unsigned char byte = 0;
  for (;;) {
    pollfd readable{.fd = signal_pipe_read_fd, .events = POLLIN, .revents = 0};
    if (::poll(&readable, 1, -1) < 0) {
      if (errno == EINTR) continue;
      throw_internal("cannot wait on the signal pipe");
    }
    const auto n = ::read(signal_pipe_read_fd, &byte, 1);
    if (n == 1) return byte;
    if (n < 0 && errno == EINTR) continue;
    throw_internal("the signal pipe closed");
  }
}

int serve_until_terminated(ServerRuntime& runtime, std::string_view service,
                           const std::function<void()>& periodic, std::chrono::milliseconds period,
                           const nlohmann::json& fields, const std::function<void()>& draining) {
  nlohmann::json listening = fields;
  listening["port"] = runtime.port();
  if (runtime.metrics_port() != 0) listening["metrics_port"] = runtime.metrics_port();
  log_event(service, "listening", listening);
  std::printf("%d\n", runtime.port());
  std::fflush(stdout);
  {
    std::jthread background([&](std::stop_token stop) {
      // Waits that a stop request ends at once: the drain does not wait out a period.
      std::mutex mutex;
      std::condition_variable_any wake;
      std::unique_lock lock(mutex);
      for (;;) {
        wake.wait_for(lock, stop, period, [] { return false; });
        if (stop.stop_requested()) return;
        periodic();
      }
    });
    const int signal = wait_for_termination_signal();
    log_event(service, "draining", {{"signal", signal}});
  }
  if (draining) draining();
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
