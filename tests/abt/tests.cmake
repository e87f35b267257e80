set(_abt ${CMAKE_CURRENT_LIST_DIR})
cullkit_add_test(test_abt_cull SOURCES ${_abt}/test_abt_cull.cpp LABELS abt)
cullkit_add_test(test_abt_build SOURCES ${_abt}/test_abt_build.cpp LABELS abt)
cullkit_add_test(test_abt_occlusion_tree SOURCES ${_abt}/test_abt_occlusion_tree.cpp LABELS abt)

# Compile-fail: the tree over a type without BoundsTraits (the shared source, built with the tree),
# and from_getter with a getter that returns no Aabb. Each must fail with cullkit's message.
function(_abt_compile_fail name source message)
  add_executable(${name} EXCLUDE_FROM_ALL ${source})
  target_link_libraries(${name} PRIVATE cullkit::cullkit)
  target_compile_definitions(${name} PRIVATE CULLKIT_COMPILE_FAIL_WITH_TREE)
  add_test(NAME ${name} COMMAND ${CMAKE_COMMAND} --build ${CMAKE_BINARY_DIR} --target ${name})
  set_tests_properties(${name} PROPERTIES WILL_FAIL TRUE LABELS "abt;compile_fail" RESOURCE_LOCK cullkit_build_dir)
  add_test(NAME ${name}_message COMMAND ${CMAKE_COMMAND} --build ${CMAKE_BINARY_DIR} --target ${name})
  set_tests_properties(${name}_message PROPERTIES LABELS "abt;compile_fail" RESOURCE_LOCK cullkit_build_dir
                       PASS_REGULAR_EXPRESSION "${message}")
endfunction()
if(CULLKIT_TESTS_COMPILE_CHECKS)
  _abt_compile_fail(compile_fail_abt_bounds_traits ${PROJECT_SOURCE_DIR}/tests/compile_fail/missing_bounds_traits.cpp
                    "no bounds for this Object type")
  _abt_compile_fail(compile_fail_abt_getter ${_abt}/compile_fail_getter.cpp "from_getter needs a callable")
endif()
cullkit_add_test(test_abt_dynamic SOURCES ${_abt}/test_abt_dynamic.cpp LABELS abt)
cullkit_add_test(test_abt_volume_scale SOURCES ${_abt}/test_abt_volume_scale.cpp LABELS abt)
