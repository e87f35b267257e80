# Depth sort tests: the radix sort against std::stable_sort with the contract's comparator.
cullkit_add_test(test_depth_sort SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_depth_sort.cpp TIMEOUT 120)
