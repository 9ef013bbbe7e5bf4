# Records the release version and the code commit in a generated header, so every run,
# checkpoint and `--version` can say which code produced it. Refreshed at every build, not only at configure time: a binary
# built after a commit must not report the commit before it.
set(PNP_BUILD_INFO_HEADER ${CMAKE_BINARY_DIR}/generated/build_info.h)
add_custom_target(pnp_build_info_header ALL
  COMMAND ${CMAKE_COMMAND} -DSOURCE_DIR=${PROJECT_SOURCE_DIR} -DOUTPUT=${PNP_BUILD_INFO_HEADER}
          -DVERSION=${PROJECT_VERSION}
          -P ${PROJECT_SOURCE_DIR}/cmake/write_build_info.cmake
  BYPRODUCTS ${PNP_BUILD_INFO_HEADER}
  COMMENT "Recording the code commit")
add_library(pnp_build_info INTERFACE)
add_dependencies(pnp_build_info pnp_build_info_header)
target_include_directories(pnp_build_info INTERFACE ${CMAKE_BINARY_DIR}/generated)
