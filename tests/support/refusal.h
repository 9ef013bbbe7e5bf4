#pragma once
// The message of the INVALID_ARGUMENT a call must throw (a test failure if it throws
// nothing or another code): refusal tests compare it with the exact text users see. And
// the code any pnp::Error a call must throw, with its message.

#include <gtest/gtest.h>

#include <functional>
#include <string>

#include "common/error.h"

namespace pnp::testing {

inline std::string refusal(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    return e.what();
  }
  ADD_FAILURE() << "expected an INVALID_ARGUMENT";
  return "";
}

// The code `fn` throws (a test failure if it throws nothing), its message in `message`.
inline ErrorCode code_of(const std::function<void()>& fn, std::string* message = nullptr) {
  try {
    fn();
  } catch (const Error& e) {
    if (message) *message = e.what();
    return e.code();
  }
  ADD_FAILURE() << "did not throw";
  return ErrorCode::kInternal;
}

}  // namespace pnp::testing
