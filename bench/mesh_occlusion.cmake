cullkit_add_bench(bench_mesh_occlusion SOURCES ${CMAKE_CURRENT_LIST_DIR}/bench_mesh_occlusion.cpp EMBREE)

# The live race against Intel's Masked Occlusion Culling (bench_mesh_occlusion --moc), when
# CULLKIT_MOC_DIR names a folder holding its sources. They are copied into the build folder and
# built there with their own per-file flags; g++ 11 and later need two small changes to the copy
# (the compiler's <cpuid.h> already defines __cpuidex, and its _xgetbv helper clashes with the
# compiler's intrinsic). Without the folder, the race is left out and the benchmark runs as before.
set(CULLKIT_MOC_DIR "" CACHE PATH "Folder of Intel's Masked Occlusion Culling sources to race in bench_mesh_occlusion")
if(TARGET bench_mesh_occlusion AND CULLKIT_MOC_DIR)
  if(NOT EXISTS "${CULLKIT_MOC_DIR}/MaskedOcclusionCulling.cpp")
    message(STATUS "cullkit: CULLKIT_MOC_DIR=${CULLKIT_MOC_DIR} holds no MaskedOcclusionCulling.cpp; MOC race left out")
  else()
    set(moc_copy "${CMAKE_CURRENT_BINARY_DIR}/moc_peer")
    file(MAKE_DIRECTORY "${moc_copy}")
    set(moc_gcc11 OFF)
    if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_GREATER_EQUAL 11)
      set(moc_gcc11 ON)
    endif()
    foreach(f MaskedOcclusionCulling.h MaskedOcclusionCulling.cpp MaskedOcclusionCullingAVX2.cpp
              MaskedOcclusionCullingAVX512.cpp MaskedOcclusionCullingCommon.inl CompilerSpecific.inl)
      file(READ "${CULLKIT_MOC_DIR}/${f}" text)
      string(REPLACE "_xgetbv" "moc_peer_xgetbv" text "${text}")
      if(moc_gcc11)
        string(REPLACE "FORCE_INLINE void __cpuidex(" "FORCE_INLINE void moc_peer_unused_cpuidex(" text "${text}")
      endif()
      file(WRITE "${moc_copy}/${f}.new" "${text}")
      # Rewritten only when changed, so that a reconfigure does not rebuild the peer.
      configure_file("${moc_copy}/${f}.new" "${moc_copy}/${f}" COPYONLY)
    endforeach()
    add_library(cullkit_moc_peer STATIC
      "${moc_copy}/MaskedOcclusionCulling.cpp" "${moc_copy}/MaskedOcclusionCullingAVX2.cpp"
      "${moc_copy}/MaskedOcclusionCullingAVX512.cpp" "${CMAKE_CURRENT_LIST_DIR}/moc_peer.cpp")
    target_include_directories(cullkit_moc_peer PRIVATE "${moc_copy}")
    # MOC's own per-file flags, -O3, and none of the project's warnings (it is not the project's code).
    # Its base file must target the lowest instruction set it dispatches from, whatever -march the
    # project is built with: the generic target comes after the build's flags and before the file's.
    target_compile_options(cullkit_moc_peer PRIVATE -march=x86-64 -mtune=generic -O3 -w)
    set_source_files_properties("${moc_copy}/MaskedOcclusionCulling.cpp" "${CMAKE_CURRENT_LIST_DIR}/moc_peer.cpp"
                                PROPERTIES COMPILE_OPTIONS "-msse4.1")
    set_source_files_properties("${moc_copy}/MaskedOcclusionCullingAVX2.cpp" PROPERTIES COMPILE_OPTIONS "-mavx2;-mfma;-msse4.1")
    set_source_files_properties("${moc_copy}/MaskedOcclusionCullingAVX512.cpp" PROPERTIES
                                COMPILE_OPTIONS "-DUSE_AVX512=1;-mavx512f;-mavx512bw;-mavx512dq;-mavx2;-mfma;-msse4.1")
    target_link_libraries(bench_mesh_occlusion PRIVATE cullkit_moc_peer)
    target_compile_definitions(bench_mesh_occlusion PRIVATE CULLKIT_BENCH_MOC=1)
    message(STATUS "cullkit: bench_mesh_occlusion races MOC from ${CULLKIT_MOC_DIR}")
  endif()
endif()
