cullkit_add_bench(bench_box_proxy SOURCES ${CMAKE_CURRENT_LIST_DIR}/bench_box_proxy.cpp)
