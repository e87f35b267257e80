// The source of the target that builds the tests' shared precompiled header (tests/CMakeLists.txt):
// a target needs a source for its header to be compiled; the tests reuse the result.
