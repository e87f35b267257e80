set(_abt ${CMAKE_CURRENT_LIST_DIR})
cullkit_add_test(test_abt_cull SOURCES ${_abt}/test_abt_cull.cpp LABELS abt)
cullkit_add_test(test_abt_build SOURCES ${_abt}/test_abt_build.cpp LABELS abt)
