#include "common/error.h"

#include <string>

namespace pnp {

std::string_view to_string(ErrorCode code) {
  switch (code) {
    case ErrorCode::kInvalidArgument:
      return "INVALID_ARGUMENT";
    case ErrorCode::kNotFound:
      return "NOT_FOUND";
    case ErrorCode::kFailedPrecondition:
      return "FAILED_PRECONDITION";
    case ErrorCode::kResourceExhausted:
      return "RESOURCE_EXHAUSTED";
    case ErrorCode::kDataLoss:
      return "DATA_LOSS";
    case ErrorCode::kUnavailable:
      return "UNAVAILABLE";
    case ErrorCode::kAborted:
      return "ABORTED";
    case ErrorCode::kCancelled:
      return "CANCELLED";
    case ErrorCode::kPermissionDenied:
      return "PERMISSION_DENIED";
    case ErrorCode::kInternal:
      return "INTERNAL";
  }
  return "UNKNOWN";
}

void throw_invalid_argument(std::string_view field, std::string_view expected,
                            std::string_view got) {
  std::string message;
  message.append(field).append(": expected ").append(expected).append(", got ").append(got);
  throw Error(ErrorCode::kInvalidArgument, message);
}

void throw_failed_precondition(std::string_view message) {
  throw Error(ErrorCode::kFailedPrecondition, std::string(message));
}

void throw_internal(std::string_view message) {
  throw Error(ErrorCode::kInternal, std::string(message));
}

}  // namespace pnp
