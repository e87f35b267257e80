cullkit_add_bench(bench_nci SOURCES ${CMAKE_CURRENT_LIST_DIR}/bench_nci.cpp EMBREE)
