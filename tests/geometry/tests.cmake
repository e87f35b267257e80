set(_geo ${CMAKE_CURRENT_LIST_DIR})
cullkit_add_test(test_aabb_plane_sphere SOURCES ${_geo}/test_aabb_plane_sphere.cpp)
cullkit_add_test(test_convex_polygon SOURCES ${_geo}/test_convex_polygon.cpp)
cullkit_add_test(test_camera SOURCES ${_geo}/test_camera.cpp)
cullkit_add_test(test_traits SOURCES ${_geo}/test_traits.cpp)
cullkit_add_test(test_convex_volume SOURCES ${_geo}/test_convex_volume.cpp)
# The same frustum test compiled with GLM's clip-control macros off and on. Separate programs:
# GLM's own inline functions change meaning with these macros, so they may not share one program.
cullkit_add_test(test_frustum SOURCES ${_geo}/test_frustum.cpp)
cullkit_add_test(test_frustum_glm_zo_lh NO_PCH SOURCES ${_geo}/test_frustum.cpp)
target_compile_definitions(test_frustum_glm_zo_lh PRIVATE GLM_FORCE_DEPTH_ZERO_TO_ONE GLM_FORCE_LEFT_HANDED)
# The bit primitives with the compiler's intrinsics, and with the portable fallbacks forced.
cullkit_add_test(test_bits SOURCES ${_geo}/test_bits.cpp)
cullkit_add_test(test_bits_portable NO_PCH SOURCES ${_geo}/test_bits.cpp)
target_compile_definitions(test_bits_portable PRIVATE CULLKIT_PORTABLE_BITS)
