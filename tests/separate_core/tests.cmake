# CULLKIT_SEPARATE_CORE: the same program with inline cores and with cullkit::core, same answers.
set(_sep ${CMAKE_CURRENT_LIST_DIR})
find_package(Threads REQUIRED)
foreach(mode inline separate)
  add_executable(separate_core_check_${mode} ${_sep}/check.cpp ${_sep}/second_unit.cpp)
  target_link_libraries(separate_core_check_${mode} PRIVATE cullkit::cullkit cullkit_warnings Threads::Threads)
endforeach()
target_link_libraries(separate_core_check_separate PRIVATE cullkit::core)
add_test(NAME test_separate_core
         COMMAND ${CMAKE_COMMAND} -DINLINE=$<TARGET_FILE:separate_core_check_inline>
                 -DSEPARATE=$<TARGET_FILE:separate_core_check_separate> -P ${_sep}/compare.cmake)
set_tests_properties(test_separate_core PROPERTIES TIMEOUT 300 LABELS engine)
