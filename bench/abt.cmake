# AdaptiveBinaryTree races: btDbvt (Bullet) and a SoA scan for culling, Embree for the build.
cullkit_add_bench(bench_abt SOURCES ${CMAKE_CURRENT_LIST_DIR}/bench_abt.cpp BULLET EMBREE)
