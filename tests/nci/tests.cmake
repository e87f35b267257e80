# NormalClassIndex tests (issue #6).
find_package(Threads REQUIRED)
cullkit_add_test(test_nci_bruteforce SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_nci_bruteforce.cpp
                 LIBS Threads::Threads)
