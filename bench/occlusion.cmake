cullkit_add_bench(bench_occlusion SOURCES ${CMAKE_CURRENT_LIST_DIR}/bench_occlusion.cpp)
