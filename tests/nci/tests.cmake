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
cullkit_add_test(test_nci_moving_affine SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_moving_affine.cpp EMBREE
                 LIBS Threads::Threads)
cullkit_add_test(test_nci_moving_far_plane SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_moving_far_plane.cpp
                 LIBS Threads::Threads)
cullkit_add_test(test_nci_moving_random SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_moving_random.cpp LIBS Threads::Threads)
# Every NormalClassIndex test builds its static index through nci_test::TestIndex (nci_index.hpp),
# which takes env CULLKIT_NCI_CROWDED_PATH (walk, rays, auto) as NciParams::crowded_path whatever the
# test's own parameters say (the paths must give the same answers).
cullkit_add_test(test_nci_crowded SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_crowded.cpp EMBREE LIBS Threads::Threads)
