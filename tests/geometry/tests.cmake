cullkit_add_test(test_geometry SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_geometry.cpp)
