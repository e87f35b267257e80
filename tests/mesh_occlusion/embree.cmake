# MeshOcclusionCuller against Embree on the generated and real scenes (walks and hard cameras).
find_package(Threads REQUIRED)
cullkit_add_test(test_mesh_occlusion_embree SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_embree.cpp EMBREE
                 LIBS Threads::Threads TIMEOUT 600 LABELS mesh_occlusion)
# MeshObject::occludes and set_occludes: see-through objects hide nothing (Embree passes through them).
cullkit_add_test(test_mesh_occlusion_see_through SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_see_through.cpp EMBREE
                 TIMEOUT 600 LABELS mesh_occlusion)
# MeshOcclusionContext::is_hidden: random boxes (through the near plane, across the sides, oriented)
# against Embree truth.
cullkit_add_test(test_mesh_occlusion_box_query SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_box_query.cpp EMBREE
                 LIBS Threads::Threads TIMEOUT 600 LABELS mesh_occlusion)
# Moving occluders (walls, vehicles, doors; mirrored, scaled) against Embree truth.
cullkit_add_test(test_mesh_occlusion_moving SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_moving.cpp EMBREE
                 TIMEOUT 600 LABELS mesh_occlusion)
# A culler built from instances (prefabs placed by matrices, mirrored ones) equals the level by hand.
cullkit_add_test(test_mesh_occlusion_instances SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_mesh_occlusion_instances.cpp EMBREE
                 TIMEOUT 300 LABELS mesh_occlusion)
