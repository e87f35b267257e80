# AdaptiveBinaryTree races: btDbvt (Bullet) and a SoA scan for culling, Embree for the build.
# The `embree` imported target is directory-scoped: find it here too so `EMBREE` links it.
find_package(embree 3 CONFIG QUIET)
cullkit_add_bench(bench_abt SOURCES ${CMAKE_CURRENT_LIST_DIR}/bench_abt.cpp BULLET EMBREE)
