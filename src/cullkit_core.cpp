// The one translation unit that compiles cullkit's non-template cores when the library is used
// with CULLKIT_SEPARATE_CORE (see config.hpp). The CMake target cullkit::core builds it; a project
// that takes the headers some other way compiles a file with these two lines itself.
#define CULLKIT_IMPLEMENTATION
#include <cullkit/cullkit.hpp>
