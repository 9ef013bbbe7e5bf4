#include "services/common/status.h"

#include <array>

namespace pnp::services {

grpc::StatusCode status_code(ErrorCode code) {
  switch (code) {
    case ErrorCode::kInvalidArgument:
      return grpc::StatusCode::INVALID_ARGUMENT;
    case ErrorCode::kNotFound:
      return grpc::StatusCode::NOT_FOUND;
    case ErrorCode::kFailedPrecondition:
      return grpc::StatusCode::FAILED_PRECONDITION;
    case ErrorCode::kResourceExhausted:
      return grpc::StatusCode::RESOURCE_EXHAUSTED;
    case ErrorCode::kDataLoss:
      return grpc::StatusCode::DATA_LOSS;
    case ErrorCode::kUnavailable:
      return grpc::StatusCode::UNAVAILABLE;
    case ErrorCode::kAborted:
      return grpc::StatusCode::ABORTED;
    case ErrorCode::kCancelled:
      return grpc::StatusCode::CANCELLED;
    case ErrorCode::kPermissionDenied:
      return grpc::StatusCode::PERMISSION_DENIED;
    case ErrorCode::kInternal:
      return grpc::StatusCode::INTERNAL;
  }
  return grpc::StatusCode::UNKNOWN;
}

std::string_view status_code_name(grpc::StatusCode code) {
  static constexpr std::array<std::string_view, grpc::StatusCode::UNAUTHENTICATED + 1> kNames = {
      "OK",
      "CANCELLED",
      "UNKNOWN",
      "INVALID_ARGUMENT",
      "DEADLINE_EXCEEDED",
      "NOT_FOUND",
      "ALREADY_EXISTS",
      "PERMISSION_DENIED",
      "RESOURCE_EXHAUSTED",
      "FAILED_PRECONDITION",
      "ABORTED",
      "OUT_OF_RANGE",
      "UNIMPLEMENTED",
      "INTERNAL",
      "UNAVAILABLE",
      "DATA_LOSS",
      "UNAUTHENTICATED"};
  const int index =
      code >= 0 && code < static_cast<int>(kNames.size()) ? code : grpc::StatusCode::UNKNOWN;
  return kNames[static_cast<std::size_t>(index)];
}

std::string transport_hint(const grpc::Status& status) {
  if (status.error_code() != grpc::StatusCode::UNAVAILABLE) return {};
  const std::string& text = status.error_message();
  if (text.find("Socket closed") != std::string::npos) {
    return "the server closed the connection at once: if it serves TLS, dial it with --tls-ca "
           "(and --tls-cert/--tls-key or --token-file if it authenticates clients)";
  }
  if (text.find("Handshake") != std::string::npos || text.find("handshake") != std::string::npos ||
      text.find("SSL") != std::string::npos) {
    return "the TLS handshake failed: if the server serves plaintext (loopback), drop --tls-ca; "
           "otherwise check that --tls-ca signed its certificate and the name dialled is in it "
           "(--tls-server-name)";
  }
  return {};
}

void throw_if_error(const grpc::Status& status, std::string_view what, std::string_view address) {
  if (status.ok()) return;
  const std::string hint = transport_hint(status);
  const std::string message = std::string(what) + " (" + std::string(address) +
                              "): " + std::string(status_code_name(status.error_code())) + ": " +
                              status.error_message() + (hint.empty() ? "" : "\n(" + hint + ")");
  switch (status.error_code()) {
    case grpc::StatusCode::INVALID_ARGUMENT:
      throw Error(ErrorCode::kInvalidArgument, message);
    case grpc::StatusCode::NOT_FOUND:
      throw Error(ErrorCode::kNotFound, message);
    case grpc::StatusCode::FAILED_PRECONDITION:
      throw Error(ErrorCode::kFailedPrecondition, message);
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      throw Error(ErrorCode::kResourceExhausted, message);
    case grpc::StatusCode::DATA_LOSS:
      throw Error(ErrorCode::kDataLoss, message);
    case grpc::StatusCode::CANCELLED:
      throw Error(ErrorCode::kCancelled, message);
    case grpc::StatusCode::ABORTED:
      throw Error(ErrorCode::kAborted, message);
    case grpc::StatusCode::PERMISSION_DENIED:
    case grpc::StatusCode::UNAUTHENTICATED:
      throw Error(ErrorCode::kPermissionDenied, message);
    case grpc::StatusCode::UNAVAILABLE:
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      throw Error(ErrorCode::kUnavailable, message);
    default:
      throw Error(ErrorCode::kInternal, message);
  }
}

}  // namespace pnp::services
