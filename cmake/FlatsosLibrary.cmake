# flatsos_add_library(<folder> <sources...>): the library of one folder as target
# flatsos_<folder> (alias and exported name flatsos::<folder>), C++17, public headers in
# <folder>/include, strict warnings, installed and exported in flatsosTargets.
function(flatsos_add_library folder)
  set(target flatsos_${folder})
  add_library(${target} ${ARGN})
  add_library(flatsos::${folder} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${folder} OUTPUT_NAME ${target})
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_compile_features(${target} PUBLIC cxx_std_17)
  flatsos_set_warnings(${target})
  install(TARGETS ${target} EXPORT flatsosTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()
