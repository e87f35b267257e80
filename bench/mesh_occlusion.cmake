cullkit_add_bench(bench_mesh_occlusion SOURCES ${CMAKE_CURRENT_LIST_DIR}/bench_mesh_occlusion.cpp EMBREE)
