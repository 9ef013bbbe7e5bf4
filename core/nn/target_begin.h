// Compiles every function defined from here to nn/target_end.h for the instruction sets
// in PNP_TARGET (a GCC/Clang target string), whatever the build's -march: one binary then
// carries kernels for several CPUs and picks one at run time. Include after every other
// header, so that no inline library code is emitted for a CPU that may lack the set.
// No include guard: a file brackets its kernel with begin and end.

#ifndef PNP_TARGET
#error "define PNP_TARGET before including nn/target_begin.h"
#endif

// Pragmas do not expand macros: _Pragma on a stringised argument, expanded first.
#define PNP_PRAGMA(text) _Pragma(#text)
#if defined(__clang__)
#define PNP_TARGET_PUSH(isa) \
  PNP_PRAGMA(clang attribute push(__attribute__((target(isa))), apply_to = function))
PNP_TARGET_PUSH(PNP_TARGET)
#elif defined(__GNUC__)
#define PNP_TARGET_PUSH(isa) PNP_PRAGMA(GCC target(isa))
#pragma GCC push_options
PNP_TARGET_PUSH(PNP_TARGET)
#else
#error "the per-function target needs GCC or Clang"
#endif
#undef PNP_TARGET_PUSH
#undef PNP_PRAGMA
