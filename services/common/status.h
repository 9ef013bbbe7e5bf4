#pragma once
// The one place core errors become gRPC statuses: every handler runs its body through
// `guarded`, so a refusal from the core reaches the client as the canonical code with
// the core's message (which names the field), and nothing escapes as a crash.

#include <grpcpp/grpcpp.h>

#include <exception>
#include <string>
#include <string_view>

#include "common/error.h"

namespace pnp::services {

grpc::StatusCode status_code(ErrorCode code);
// The canonical name ("INVALID_ARGUMENT"); codes outside the canonical set read UNKNOWN.
std::string_view status_code_name(grpc::StatusCode code);

// The client's side: a failed call becomes an Error "<what> (<address>): <CODE>: <message>"
// with the matching core code (a lost or slow server is UNAVAILABLE).
void throw_if_error(const grpc::Status& status, std::string_view what, std::string_view address);

// What to do about an UNAVAILABLE status gRPC describes in transport terms: a server that
// closed the connection at once (a plaintext client at a TLS server), or a TLS handshake
// that failed (a TLS client at a plaintext server, or the wrong CA); empty otherwise.
std::string transport_hint(const grpc::Status& status);

template <typename Body>
grpc::Status guarded(Body&& body) {
  try {
    return body();
  } catch (const Error& e) {
    return {status_code(e.code()), e.what()};
  } catch (const std::bad_alloc&) {
    return {grpc::StatusCode::RESOURCE_EXHAUSTED, "out of memory"};
  } catch (const std::exception& e) {
    return {grpc::StatusCode::INTERNAL, e.what()};
  }
}

}  // namespace pnp::services
