# BspTree tests: brute-force ray oracle, and the proof by a real rasterizer (Mesa's OSMesa).
find_package(Threads REQUIRED)
cullkit_add_test(test_bsp_bruteforce SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_bsp_bruteforce.cpp
                 LIBS Threads::Threads TIMEOUT 200)
