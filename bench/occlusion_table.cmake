cullkit_add_bench(bench_occlusion_table SOURCES ${CMAKE_CURRENT_LIST_DIR}/occlusion_table.cpp EMBREE)
