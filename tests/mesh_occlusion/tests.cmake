# MeshOcclusionCuller tests: fusion of occluders, brute-force oracle on random scenes, bad input.
cullkit_add_test(test_mesh_occlusion_fusion SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_fusion.cpp TIMEOUT 300)
cullkit_add_test(test_mesh_occlusion_bruteforce SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_bruteforce.cpp TIMEOUT 300)
find_package(Threads REQUIRED)
cullkit_add_test(test_mesh_occlusion_input SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_input.cpp LIBS Threads::Threads)
# A measuring tool for docs/mesh_occlusion.md on the real scenes (not a test; needs Embree).
if(TARGET cullkit_oracle)
  add_executable(measure_mesh_occlusion ${CMAKE_CURRENT_LIST_DIR}/measure_mesh_occlusion.cpp)
  target_link_libraries(measure_mesh_occlusion PRIVATE cullkit::cullkit cullkit_warnings cullkit_support cullkit_oracle)
  target_include_directories(measure_mesh_occlusion PRIVATE ${CMAKE_CURRENT_LIST_DIR}/..)
endif()
# MeshOcclusionCuller against Embree on real and generated scenes.
include(${CMAKE_CURRENT_LIST_DIR}/embree.cmake)
