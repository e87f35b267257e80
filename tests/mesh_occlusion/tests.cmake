include(${CMAKE_CURRENT_LIST_DIR}/embree.cmake)
