# NormalClassIndex tests.
find_package(Threads REQUIRED)
cullkit_add_test(test_nci_bruteforce SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_bruteforce.cpp
                 LIBS Threads::Threads)
cullkit_add_test(test_nci_embree SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_embree.cpp EMBREE
                 LIBS Threads::Threads)
cullkit_add_test(test_nci_input SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_input.cpp LIBS Threads::Threads)
cullkit_add_test(test_nci_moving SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_moving.cpp LIBS Threads::Threads)
cullkit_add_test(test_nci_layout SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_layout.cpp LIBS Threads::Threads)
cullkit_add_test(test_nci_footprint SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_footprint.cpp LIBS Threads::Threads)
cullkit_add_test(test_nci_narrow SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_narrow.cpp EMBREE LIBS Threads::Threads)
cullkit_add_test(test_nci_precision SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_precision.cpp EMBREE
                 LIBS Threads::Threads)
cullkit_add_test(test_nci_moving_narrow SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_moving_narrow.cpp EMBREE
                 LIBS Threads::Threads)
cullkit_add_test(test_nci_warm_frames SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_warm_frames.cpp LIBS Threads::Threads)
cullkit_add_test(test_nci_mesh_input SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_mesh_input.cpp LIBS Threads::Threads)
# test_nci_crowded is built but not listed in CTest: its checks that the ray path serves crowded
# cells (NciSelectStats::cells_ray_cast) need the per-cell hierarchies, which this index lacks.
if(TARGET cullkit_oracle)
  add_executable(test_nci_crowded ${CMAKE_CURRENT_LIST_DIR}/test_nci_crowded.cpp)
  target_link_libraries(test_nci_crowded PRIVATE cullkit::cullkit cullkit_warnings cullkit_support cullkit_oracle
                        Threads::Threads)
  target_include_directories(test_nci_crowded PRIVATE ${CMAKE_CURRENT_LIST_DIR}/..)
endif()
