# MeshOcclusionCuller tests: fusion of occluders, brute-force oracle on random scenes, bad input.
cullkit_add_test(test_mesh_occlusion_fusion SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_fusion.cpp TIMEOUT 300)
cullkit_add_test(test_mesh_occlusion_bruteforce SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_bruteforce.cpp TIMEOUT 300)
find_package(Threads REQUIRED)
cullkit_add_test(test_mesh_occlusion_input SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_input.cpp LIBS Threads::Threads)
# One cull on several tasks gives the one-thread answer, on every job system and task order.
cullkit_add_test(test_mesh_occlusion_threads SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_threads.cpp LIBS Threads::Threads TIMEOUT 300)
# A warm context allocates nothing per frame, on generated and real scenes.
cullkit_add_test(test_mesh_occlusion_warm_frames SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_warm_frames.cpp TIMEOUT 300)
# MeshOcclusionCuller against Embree on real and generated scenes.
include(${CMAKE_CURRENT_LIST_DIR}/embree.cmake)
# Surface patches, triangle-level object tests and solid-box occluders, each against its control.
cullkit_add_test(test_mesh_occlusion_patches SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_patches.cpp TIMEOUT 300)
# Occluder triangles clipped at the near plane: floors and walls reaching behind the eye.
cullkit_add_test(test_mesh_occlusion_nearclip SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_nearclip.cpp TIMEOUT 300)
# The T-junction cuts' exact test and ear clipping on their own.
cullkit_add_test(test_mesh_occlusion_tjunctions SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_tjunctions.cpp)
# Per-patch layers: a wall standing on a floor that goes in before it; the control without them.
cullkit_add_test(test_mesh_occlusion_layers SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_layers.cpp TIMEOUT 300)
# Objects long in depth behind a slanted occluder: hidden cell by cell, not by their rectangle.
cullkit_add_test(test_mesh_occlusion_slanted SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_slanted.cpp TIMEOUT 300)
# The coverage grid alone against points: fans and loose triangles on a quarter-cell lattice.
cullkit_add_test(test_mesh_occlusion_coverage_grid SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_coverage_grid.cpp)
# The coverage grid's margins at rounding level: edges from corners far off the grid passing cell
# corners by a hair, checked exactly at every covered cell's corners.
cullkit_add_test(test_mesh_occlusion_margins SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_margins.cpp)
# A patch straight into the union where it is untouched, against its own grid added into the union.
cullkit_add_test(test_mesh_occlusion_direct SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_direct.cpp)
