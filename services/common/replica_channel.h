#pragma once
// How a client reaches a service whose replicas are interchangeable (inference): gRPC
// balances calls over every address the target resolves to (round_robin; with
// "dns:///pnp-inference:50060", every replica behind the name, followed as they come and
// go), and retries the idempotent calls (Predict, GetServingStatus, Ping, the health
// Check) on UNAVAILABLE, so a replica that goes away costs a caller a retry, not an error.
// A PredictSession stream stays on the replica it began on, and with it its policy.

#include <grpcpp/grpcpp.h>

#include <string_view>

namespace pnp::services {

// The service config (gRPC's JSON, proto/pnp/policy/v1/replica_service_config.json, shared
// with the Python client) that does it.
std::string_view replica_service_config();

// Sets it on `args` (which keep their other settings).
void balance_over_replicas(grpc::ChannelArguments& args);

}  // namespace pnp::services
