# Sanitizer and fuzzing builds (scripts/test.sh --sanitize runs both).
#
# FLATSOS_SANITIZE=ON: AddressSanitizer + UndefinedBehaviorSanitizer for every target of this
#   project (libraries, tests, examples), plus float-cast-overflow (double -> int out of range,
#   NaN included), which gcc's `undefined` leaves out. Any report aborts. Debian's prebuilt
#   libraries (Simbody, Ipopt, MUMPS, libstdc++) are not instrumented; ASan still intercepts
#   their malloc/new/free.
# FLATSOS_FUZZ=ON (clang only, implies FLATSOS_SANITIZE): also coverage instrumentation for
#   libFuzzer (-fsanitize=fuzzer-no-link) and the fuzz targets in tests/fuzz/.
# Include this before add_subdirectory() of the libraries: the options apply to targets created
# afterwards. Never add -DNDEBUG here (Debian's Simbody 3.7 changes its State layout with it).
option(FLATSOS_SANITIZE "Build flatsos with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)
option(FLATSOS_FUZZ "Build the libFuzzer targets in tests/fuzz (clang; implies FLATSOS_SANITIZE)"
  OFF)

set(FLATSOS_SANITIZER_FLAGS "")
if(FLATSOS_SANITIZE OR FLATSOS_FUZZ)
  set(FLATSOS_SANITIZER_FLAGS -fsanitize=address,undefined,float-cast-overflow
    -fno-sanitize-recover=undefined,float-cast-overflow)
  # -O1 -g1 after the build type's flags (the later ones win): what AddressSanitizer's reports
  # need (line tables, frame pointers, no inlining of most frames) and no more. With the build
  # type's -O2 -g the controller's source took 136 s to compile; with -O1 -g1, 35 s. The whole
  # sanitizer build took over an hour on two cores, most of CI's 90 minutes.
  add_compile_options(${FLATSOS_SANITIZER_FLAGS} -fno-omit-frame-pointer -O1 -g1)
  add_link_options(${FLATSOS_SANITIZER_FLAGS})
endif()

if(FLATSOS_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "FLATSOS_FUZZ needs clang with libFuzzer (Debian: clang "
      "libclang-rt-14-dev): configure with -DCMAKE_CXX_COMPILER=clang++")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()

# flatsos_export_sanitizer_flags(<targets...>): whoever uses the libraries of a sanitizer build
# (the installed package too: tests/package) must compile and link with the same flags: the
# static libraries need the sanitizer runtimes, and Eigen's heap functions differ under ASan
# (Eigen/src/Core/util/Memory.h: no EIGEN_MALLOC_ALREADY_ALIGNED with __SANITIZE_ADDRESS__), so a
# vector allocated in a library and freed in uninstrumented code is a bad free.
function(flatsos_export_sanitizer_flags)
  if(FLATSOS_SANITIZER_FLAGS)
    foreach(target IN LISTS ARGN)
      target_compile_options(${target} INTERFACE ${FLATSOS_SANITIZER_FLAGS})
      target_link_options(${target} INTERFACE ${FLATSOS_SANITIZER_FLAGS})
    endforeach()
  endif()
endfunction()
