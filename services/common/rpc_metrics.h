#pragma once
// Per-RPC metrics as a gRPC server interceptor: every call, unary or streaming, is counted
// once when the server sends its final status, labelled with the full method name and the
// status code name:
//   pnp_rpc_requests_total{method,code}     counter
//   pnp_rpc_duration_seconds{method,code}   histogram, 50 us to 10 s
//   pnp_rpc_in_flight{method}               gauge
// Calls to methods no service registers carry method="unregistered": the client chooses
// those names, and label values must stay a bounded set.

#include <grpcpp/support/server_interceptor.h>

#include <memory>
#include <string_view>

#include "services/common/metrics_registry.h"

namespace pnp::services {

// For ServerBuilder::experimental().SetInterceptorCreators; `registry` must outlive the
// server.
std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> make_rpc_metrics_factory(
    MetricsRegistry& registry);

}  // namespace pnp::services
