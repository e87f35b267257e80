# BspTree tests: brute-force ray oracle, and the proof by a real rasterizer (Mesa's OSMesa).
find_package(Threads REQUIRED)
cullkit_add_test(test_bsp_bruteforce SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_bsp_bruteforce.cpp
                 LIBS Threads::Threads TIMEOUT 200)
# The rasterizer proof needs OSMesa (Debian libosmesa6-dev); skipped with a message without it.
find_package(PkgConfig QUIET)
if(PkgConfig_FOUND)
  pkg_check_modules(CULLKIT_OSMESA QUIET IMPORTED_TARGET osmesa)
endif()
if(CULLKIT_OSMESA_FOUND)
  cullkit_add_test(test_bsp_osmesa SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_bsp_osmesa.cpp
                   LIBS PkgConfig::CULLKIT_OSMESA Threads::Threads TIMEOUT 300)
  # Mesa keeps a few hundred bytes of its own for the process's lifetime: not ours to report.
  set_tests_properties(test_bsp_osmesa PROPERTIES ENVIRONMENT
                       "LSAN_OPTIONS=suppressions=${CMAKE_CURRENT_LIST_DIR}/lsan_osmesa.supp")
else()
  message(STATUS "cullkit: skipping test_bsp_osmesa (OSMesa not found: install libosmesa6-dev)")
endif()
# Coverage of every triangle by its fragments, on stress scenes and every real scene present.
cullkit_add_test(test_bsp_coverage SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_bsp_coverage.cpp
                 LIBS Threads::Threads TIMEOUT 600)
