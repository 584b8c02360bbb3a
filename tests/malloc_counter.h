#pragma once
// Heap allocations counted by interposing glibc's malloc family in the test programs that link
// tests/malloc_counter.cpp. Not under the sanitizers, which own malloc.

#include <cstddef>  // brings in <features.h>, which defines __GLIBC__

// Whether a sanitizer owns malloc: GCC says so with __SANITIZE_ADDRESS__, clang with __has_feature.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define HNN_SANITIZED_MALLOC 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define HNN_SANITIZED_MALLOC 1
#endif
#endif
#ifndef HNN_SANITIZED_MALLOC
#define HNN_SANITIZED_MALLOC 0
#endif
#if HNN_SANITIZED_MALLOC || !defined(__GLIBC__)
#define HNN_COUNTS_ALLOCATIONS 0
#else
#define HNN_COUNTS_ALLOCATIONS 1
#endif

namespace hnn::testing {
/// Allocations by every thread since the program started (0 when not counting).
long allocation_count();
}  // namespace hnn::testing
