# Compile-fail tests: each target is excluded from the build; the test builds it and expects the
# compiler to stop with cullkit's static_assert message AND to name the user's type.
function(cullkit_compile_fail name source message type)
  add_executable(${name} EXCLUDE_FROM_ALL ${source})
  target_link_libraries(${name} PRIVATE cullkit::cullkit)
  add_test(NAME ${name}
           COMMAND ${CMAKE_COMMAND} --build ${CMAKE_BINARY_DIR} --target ${name})
  set_tests_properties(${name} PROPERTIES WILL_FAIL TRUE LABELS compile_fail RESOURCE_LOCK cullkit_build_dir)
  add_test(NAME ${name}_message
           COMMAND ${CMAKE_COMMAND} --build ${CMAKE_BINARY_DIR} --target ${name})
  set_tests_properties(${name}_message PROPERTIES LABELS compile_fail RESOURCE_LOCK cullkit_build_dir
                       PASS_REGULAR_EXPRESSION "${message}")
  add_test(NAME ${name}_names_type
           COMMAND ${CMAKE_COMMAND} --build ${CMAKE_BINARY_DIR} --target ${name})
  set_tests_properties(${name}_names_type PROPERTIES LABELS compile_fail RESOURCE_LOCK cullkit_build_dir PASS_REGULAR_EXPRESSION "${type}")
endfunction()
set(_cf ${CMAKE_CURRENT_LIST_DIR})
cullkit_compile_fail(compile_fail_vertex_traits ${_cf}/missing_vertex_traits.cpp
  "no vertex position for this Vertex type" MyEngineVertexWithoutTraits)
cullkit_compile_fail(compile_fail_bounds_traits ${_cf}/missing_bounds_traits.cpp
  "no bounds for this Object type" MyEngineObjectWithoutBounds)
# The control must build, or the tests above prove nothing.
add_executable(compile_fail_control EXCLUDE_FROM_ALL ${_cf}/control_ok.cpp)
target_link_libraries(compile_fail_control PRIVATE cullkit::cullkit)
add_test(NAME compile_fail_control COMMAND ${CMAKE_COMMAND} --build ${CMAKE_BINARY_DIR} --target compile_fail_control)
set_tests_properties(compile_fail_control PROPERTIES LABELS compile_fail RESOURCE_LOCK cullkit_build_dir)
