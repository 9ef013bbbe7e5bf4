#pragma once
// What every fuzz target asserts: hostile bytes may be refused, but only with a pnp::Error
// (a canonical code and a message naming the field); anything else that escapes (another
// exception type, a crash, a sanitizer finding, a hang) is a bug. A target calls
// refuse_or_accept(fn) with the code under test.

#include <cstdio>
#include <cstdlib>
#include <exception>

#include "common/error.h"

namespace pnp::fuzz {

template <typename Fn>
void refuse_or_accept(Fn&& fn) {
  try {
    fn();
  } catch (const Error&) {  // a clear refusal: the contract
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz: escaped as %s, not pnp::Error: %s\n", typeid(e).name(), e.what());
    std::abort();
  }
}

}  // namespace pnp::fuzz
