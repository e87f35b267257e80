set(_engine ${CMAKE_CURRENT_LIST_DIR})
cullkit_add_test(test_engine_bad_bounds SOURCES ${_engine}/test_engine_bad_bounds.cpp LABELS engine)
cullkit_add_test(test_engine_camera SOURCES ${_engine}/test_engine_camera.cpp LABELS engine)
cullkit_add_test(test_engine_views SOURCES ${_engine}/test_engine_views.cpp LABELS engine)
cullkit_add_test(test_engine_refit SOURCES ${_engine}/test_engine_refit.cpp LABELS engine)
find_package(Threads REQUIRED)
cullkit_add_test(test_engine_mesh_buffers NO_PCH SOURCES ${_engine}/test_engine_mesh_buffers.cpp LIBS Threads::Threads
                 LABELS engine)
cullkit_add_test(test_engine_degenerate_camera SOURCES ${_engine}/test_engine_degenerate_camera.cpp
                 LIBS Threads::Threads LABELS engine)
