cullkit_add_test(test_oracle SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_oracle.cpp EMBREE)
cullkit_add_test(test_scene_render SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_scene_render.cpp EMBREE)
