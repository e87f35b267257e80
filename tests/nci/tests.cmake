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
# Every NormalClassIndex test takes env CULLKIT_NCI_CROWDED_PATH (walk, rays, auto) to run with that
# NciParams::crowded_path whatever its own parameters say (the paths must give the same answers).
foreach(t test_nci_bruteforce test_nci_embree test_nci_input test_nci_moving test_nci_layout test_nci_footprint
          test_nci_narrow test_nci_precision test_nci_moving_narrow test_nci_warm_frames test_nci_mesh_input
          test_nci_moving_affine test_nci_moving_far_plane test_nci_moving_random)
  if(TARGET ${t})
    target_compile_definitions(${t} PRIVATE CULLKIT_NCI_CROWDED_PATH_FROM_ENV=1)
  endif()
endforeach()
cullkit_add_test(test_nci_crowded SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_crowded.cpp EMBREE LIBS Threads::Threads)
