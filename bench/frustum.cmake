cullkit_add_bench(bench_frustum SOURCES ${CMAKE_CURRENT_LIST_DIR}/bench_frustum.cpp)
cullkit_add_bench(bench_frustum_micro SOURCES ${CMAKE_CURRENT_LIST_DIR}/bench_frustum_micro.cpp GBENCH
                  SMOKE_ARGS --benchmark_min_time=0.001)
