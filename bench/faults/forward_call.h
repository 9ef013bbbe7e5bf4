#pragma once
// One unary call forwarded to an upstream stub within the caller's own deadline.

#include <grpcpp/grpcpp.h>

namespace pnp::faults {

template <typename Stub, typename Request, typename Response>
using UnaryMethod = grpc::Status (Stub::*)(grpc::ClientContext*, const Request&, Response*);

template <typename Stub, typename Request, typename Response>
grpc::Status forward_call(const grpc::ServerContext& context, Stub& stub,
                          UnaryMethod<Stub, Request, Response> method, const Request& request,
                          Response* response) {
  grpc::ClientContext upstream;
  upstream.set_deadline(context.deadline());
  return (stub.*method)(&upstream, request, response);
}

}  // namespace pnp::faults
