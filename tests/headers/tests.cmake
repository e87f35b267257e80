# Every public header compiles on its own: one generated translation unit per header, all built
# into one object library as part of the normal build (a header that is not self-contained breaks
# the build, not just a test).
file(GLOB_RECURSE _cullkit_headers CONFIGURE_DEPENDS RELATIVE ${PROJECT_SOURCE_DIR}/include
     ${PROJECT_SOURCE_DIR}/include/cullkit/*.hpp)
set(_cullkit_header_tus "")
foreach(h ${_cullkit_headers})
  string(MAKE_C_IDENTIFIER ${h} id)
  set(tu ${CMAKE_CURRENT_BINARY_DIR}/headers/${id}.cpp)
  file(CONFIGURE OUTPUT ${tu} CONTENT "#include <${h}>\n#include <${h}>  // and include guards work\n")
  list(APPEND _cullkit_header_tus ${tu})
endforeach()
add_library(cullkit_header_check OBJECT ${_cullkit_header_tus})
target_link_libraries(cullkit_header_check PRIVATE cullkit::cullkit cullkit_warnings)
