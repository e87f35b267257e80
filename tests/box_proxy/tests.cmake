set(_box_proxy ${CMAKE_CURRENT_LIST_DIR})
cullkit_add_test(test_box_proxy SOURCES ${_box_proxy}/test_box_proxy.cpp LABELS box_proxy)
cullkit_add_test(test_box_proxy_embree SOURCES ${_box_proxy}/test_box_proxy_embree.cpp EMBREE LABELS box_proxy)
