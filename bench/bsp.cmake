cullkit_add_bench(bench_bsp SOURCES ${CMAKE_CURRENT_LIST_DIR}/bench_bsp.cpp)
