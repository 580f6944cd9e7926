# flatsos_set_warnings(<target>): strict warnings for flatsos' own code only.
# Dependencies come in through imported targets, whose headers CMake marks SYSTEM.
function(flatsos_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
    -Wno-sign-conversion)
  if(FLATSOS_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
