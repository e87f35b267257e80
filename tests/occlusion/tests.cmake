set(_occ ${CMAKE_CURRENT_LIST_DIR})
cullkit_add_test(test_occlusion_bruteforce SOURCES ${_occ}/test_occlusion_bruteforce.cpp)
cullkit_add_test(test_occlusion_embree SOURCES ${_occ}/test_occlusion_embree.cpp EMBREE)
cullkit_add_test(test_occlusion_order SOURCES ${_occ}/test_occlusion_order.cpp)
