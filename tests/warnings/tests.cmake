# The headers' template code under the warnings engines raise, as errors: instantiate_all.cpp
# instantiates every container with an engine's own types. Compiled in every preset (an object
# library: nothing to run), so g++ and clang, C++17 and C++20 all check it.
add_library(cullkit_warnings_check OBJECT ${CMAKE_CURRENT_LIST_DIR}/instantiate_all.cpp)
target_link_libraries(cullkit_warnings_check PRIVATE cullkit::cullkit cullkit_warnings)
if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
  target_compile_options(cullkit_warnings_check PRIVATE -Wconversion -Wsign-conversion -Wshadow)
endif()
