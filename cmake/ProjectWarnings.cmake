# Warnings as errors for the project's own targets only (never for system headers).
add_library(pnp_project_options INTERFACE)
target_compile_options(pnp_project_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast -Wcast-align
  -Wunused -Woverloaded-virtual -Wconversion -Wsign-conversion -Wnull-dereference
  -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough -Werror
  # GCC 12 reports std::string concatenation as overlapping memcpy (GCC bug 105329).
  $<$<AND:$<CXX_COMPILER_ID:GNU>,$<VERSION_LESS:$<CXX_COMPILER_VERSION>,13>>:-Wno-restrict>
  # GCC 12 with AVX-512 flags Eigen's inlined _mm512 intrinsics (their own `__Y = __Y`
  # idiom) as maybe-uninitialized: a false positive inside the compiler's headers.
  $<$<AND:$<CXX_COMPILER_ID:GNU>,$<VERSION_LESS:$<CXX_COMPILER_VERSION>,13>>:-Wno-maybe-uninitialized>)
if(PNP_NATIVE)
  target_compile_options(pnp_project_options INTERFACE -march=native)
endif()
# ThreadSanitizer's instrumentation changes what GCC 12 can prove: it then flags
# std::string moves inside CLI11's headers as null dereferences (false positives).
if(PNP_SANITIZE MATCHES "thread" AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  target_compile_options(pnp_project_options INTERFACE -Wno-null-dereference)
endif()
