set(_portals ${CMAKE_CURRENT_LIST_DIR})
cullkit_add_test(test_portals_bruteforce SOURCES ${_portals}/test_portals_bruteforce.cpp TIMEOUT 120)
cullkit_add_test(test_portals_office SOURCES ${_portals}/test_portals_office.cpp EMBREE TIMEOUT 200)
