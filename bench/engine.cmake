# Engine-shaped workloads: several views in one walk (cull_views) against separate culls and
# Bullet's btDbvt, the shadow-caster volume, and the repairing refit against plain refit / rebuild.
cullkit_add_bench(bench_views SOURCES ${CMAKE_CURRENT_LIST_DIR}/bench_views.cpp BULLET)
