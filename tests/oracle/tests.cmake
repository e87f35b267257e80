cullkit_add_test(test_oracle SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_oracle.cpp EMBREE)
