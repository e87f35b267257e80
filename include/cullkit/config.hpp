// cullkit/config.hpp: version, assertion hook and the few macros the library uses.
//
// Every macro cullkit reads or defines starts with CULLKIT_. None of them changes what a function
// computes; CULLKIT_ASSERT only decides how a broken precondition is reported.
#pragma once

#define CULLKIT_VERSION_MAJOR 0
#define CULLKIT_VERSION_MINOR 1
#define CULLKIT_VERSION_PATCH 0

// CULLKIT_ASSERT(condition, message): checks a documented precondition in debug builds.
// Define it before including any cullkit header to route failures to your engine's handler.
// The default uses <cassert>, so it disappears under NDEBUG. It never throws.
#ifndef CULLKIT_ASSERT
#include <cassert>
#define CULLKIT_ASSERT(condition, message) assert((condition) && (message))
#endif

#if defined(__cpp_concepts) && __cpp_concepts >= 201907L
#define CULLKIT_HAS_CONCEPTS 1
#else
#define CULLKIT_HAS_CONCEPTS 0
#endif

#if defined(__GNUC__) || defined(__clang__)
#define CULLKIT_FORCEINLINE inline __attribute__((always_inline))
#elif defined(_MSC_VER)
#define CULLKIT_FORCEINLINE __forceinline
#else
#define CULLKIT_FORCEINLINE inline
#endif

// CULLKIT_HAS_SSE2: 1 where the SSE2 intrinsics of <emmintrin.h> may be used (x86-64 always has
// them; 32-bit x86 when the compiler targets SSE2). Hot loops use them only as pre-tests or
// as the same IEEE operations as their scalar form, so the answers are the same either way.
// Define it to 0 before including cullkit to get the scalar code.
#ifndef CULLKIT_HAS_SSE2
#if defined(__SSE2__) || defined(_M_X64) || (defined(_M_IX86_FP) && _M_IX86_FP >= 2)
#define CULLKIT_HAS_SSE2 1
#else
#define CULLKIT_HAS_SSE2 0
#endif
#endif

// Separate compilation of the heavy non-template cores (opt-in). By default every core is inline:
// a translation unit that uses NormalClassIndex or the worker pool compiles their machinery itself.
// Define CULLKIT_SEPARATE_CORE in every translation unit of the program, and in exactly one of them
// also CULLKIT_IMPLEMENTATION before its first cullkit include (src/cullkit_core.cpp is that unit;
// linking the CMake target `cullkit::core` does both). The other units then see only declarations
// of the cores' entry points and skip their headers, so they compile faster, and the one unit holds
// the single definition. The answers are the same in both modes.
//   CULLKIT_CORE_FN      what a core entry point is declared with: `inline`, or nothing.
//   CULLKIT_CORE_BODIES  1 where the cores' definitions are compiled in this unit.
#if defined(CULLKIT_SEPARATE_CORE)
#define CULLKIT_CORE_FN
#if defined(CULLKIT_IMPLEMENTATION)
#define CULLKIT_CORE_BODIES 1
#else
#define CULLKIT_CORE_BODIES 0
#endif
#else
#define CULLKIT_CORE_FN inline
#define CULLKIT_CORE_BODIES 1
#endif
