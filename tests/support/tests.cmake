set(_support ${CMAKE_CURRENT_LIST_DIR})
cullkit_add_test(test_scenes SOURCES ${_support}/test_scenes.cpp)
cullkit_add_test(test_image NO_PCH SOURCES ${_support}/test_image.cpp)
if(CULLKIT_STB_INCLUDE)
  # With stb present, writing a PNG must succeed (without it, write_png returns false by contract).
  target_compile_definitions(test_image PRIVATE CULLKIT_TEST_HAVE_STB=1)
endif()
# A picture tool for eyeballing scenes (not a test): render_scene <city|office|forest|file.obj> <prefix>
if(TARGET cullkit_oracle)
  add_executable(render_scene ${_support}/render_scene.cpp)
  target_link_libraries(render_scene PRIVATE cullkit::cullkit cullkit_warnings cullkit_support cullkit_oracle)
endif()
