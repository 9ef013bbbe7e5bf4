#pragma once
// The message of the INVALID_ARGUMENT a call must throw (a test failure if it throws
// nothing or another code): refusal tests compare it with the exact text users see.

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

}  // namespace pnp::testing
