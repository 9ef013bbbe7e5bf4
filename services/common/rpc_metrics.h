#pragma once
// Per-RPC metrics as a gRPC server interceptor, with go-grpc-prometheus' names and labels
// (what Grafana's gRPC dashboards and common alert rules query): every call, unary or
// streaming, is counted when it starts and once when the server sends its final status:
//   grpc_server_started_total{grpc_type,grpc_service,grpc_method}             counter
//   grpc_server_handled_total{grpc_type,grpc_service,grpc_method,grpc_code}   counter
//   grpc_server_handling_seconds{grpc_type,grpc_service,grpc_method}          histogram, 50 us to
//   10 s
// grpc_type is unary, client_stream, server_stream or bidi_stream; grpc_code is Go's name
// of the status code (OK, InvalidArgument, ...). Calls in flight: started - handled. Calls
// to methods no service registers carry grpc_service and grpc_method "unregistered": the
// client chooses those names, and label values must stay a bounded set.

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
