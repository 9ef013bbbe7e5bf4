# Warnings as errors for the project's own targets only (never for system headers).
add_library(pnp_project_options INTERFACE)
target_compile_options(pnp_project_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast -Wcast-align
  -Wunused -Woverloaded-virtual -Wconversion -Wsign-conversion -Wnull-dereference
  -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough -Werror
  # GCC 12 reports std::string concatenation as overlapping memcpy (GCC bug 105329).
  $<$<AND:$<CXX_COMPILER_ID:GNU>,$<VERSION_LESS:$<CXX_COMPILER_VERSION>,13>>:-Wno-restrict>)
if(PNP_NATIVE)
  target_compile_options(pnp_project_options INTERFACE -march=native)
endif()
