cullkit_add_test(test_scenes SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_scenes.cpp)
