# flatsos_set_warnings(<target>): strict warnings for flatsos' own code only.
# Dependencies come in through imported targets, whose headers CMake marks SYSTEM.
function(flatsos_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
    -Wno-sign-conversion)
  # GCC 12 reports std::optional<Eigen::VectorXd> members (options' warm starts) as "maybe
  # uninitialized" when a copy is destroyed: a known false positive of -Wmaybe-uninitialized
  # (GCC bug 80635). Kept as a warning, not an error.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    target_compile_options(${target} PRIVATE -Wno-error=maybe-uninitialized)
  endif()
  if(FLATSOS_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
