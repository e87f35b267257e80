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
