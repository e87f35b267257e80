cullkit_add_bench(bench_portals SOURCES ${CMAKE_CURRENT_LIST_DIR}/bench_portals.cpp EMBREE)
