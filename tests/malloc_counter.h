#pragma once
// Heap allocations counted by interposing glibc's malloc family in the test programs that link
// tests/malloc_counter.cpp. Not under the sanitizers, which own malloc.

#include <cstddef>  // brings in <features.h>, which defines __GLIBC__

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__) || !defined(__GLIBC__)
#define HNN_COUNTS_ALLOCATIONS 0
#else
#define HNN_COUNTS_ALLOCATIONS 1
#endif

namespace hnn::testing {
/// Allocations by every thread since the program started (0 when not counting).
long allocation_count();
}  // namespace hnn::testing
