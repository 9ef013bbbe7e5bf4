#pragma once
// One exception type for every refusal the core makes. The code mirrors the canonical
// gRPC status codes so that services map it one to one, and the message always names
// the offending field and what was expected.

#include <stdexcept>
#include <string>
#include <string_view>

namespace pnp {

enum class ErrorCode {
  kInvalidArgument,     // bad input: names the field and the expected value
  kNotFound,            // unknown id or name
  kFailedPrecondition,  // right input, wrong state (e.g. step before reset)
  kResourceExhausted,   // a size or count limit
  kDataLoss,            // corrupted or truncated stored data
  kUnavailable,         // a resource is busy or unreachable: retrying may succeed
  kAborted,             // lost a race for shared state (another owner holds it): re-read
  kCancelled,           // the work was cancelled by its caller
  kPermissionDenied,    // an authenticated caller asked for what its identity may not do
  kInternal,            // a broken invariant inside the core
};

std::string_view to_string(ErrorCode code);

class Error : public std::runtime_error {
 public:
  Error(ErrorCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  ErrorCode code() const { return code_; }

 private:
  ErrorCode code_;
};

[[noreturn]] void throw_invalid_argument(std::string_view field, std::string_view expected,
                                         std::string_view got);
[[noreturn]] void throw_failed_precondition(std::string_view message);
[[noreturn]] void throw_internal(std::string_view message);

}  // namespace pnp
