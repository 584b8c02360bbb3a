// A recorded batched_solve and its backward (first and second order) allocate nothing on the
// heap once warmed up inside a reused TapeScope: the LU works in fixed-size storage for blocks up
// to 4x4 and every node's buffer is recycled. Counted by interposing glibc's malloc family in the
// autodiff test program, as tests/nn/allocation_test.cpp does in the nn one.

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <vector>

#include "autodiff/autodiff.h"
#include "test_util.h"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__) && defined(__GLIBC__)
#define HNN_COUNT_ALLOCATIONS 1

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);

void* malloc(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_realloc(p, n);
}
void* aligned_alloc(std::size_t alignment, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_memalign(alignment, n);
}
void* memalign(std::size_t alignment, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_memalign(alignment, n);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  *out = __libc_memalign(alignment, n);
  return *out ? 0 : 12;  // ENOMEM
}
}
#endif

namespace ad = hnn::ad;
using ad::Var;
using ad::testing::MatrixD;

namespace {

// Heap allocations of `steps` steps after `warmup`: x = solve(A, b), loss = sum(x^2), its
// gradient with create_graph, and the gradient of |grad|^2 (the backward's own backward).
template <typename T>
long AllocationsOfSolveSteps(Eigen::Index rows, Eigen::Index n, int warmup, int steps) {
  MatrixD a = ad::testing::random_matrix(rows, n * n, 1, -0.5, 0.5);
  for (Eigen::Index r = 0; r < rows; ++r)
    for (Eigen::Index i = 0; i < n; ++i) a(r, i * n + i) += 2.0;
  const std::vector<Var<T>> inputs = {
      Var<T>::leaf(a.cast<T>()), Var<T>::leaf(ad::testing::random_matrix(rows, n, 2).cast<T>())};
  std::vector<Var<T>> first, second;
  long counted = 0;
  for (int step = 0; step < warmup + steps; ++step) {
    const long before = g_allocations.load();
    {
      ad::TapeScope scope;
      const Var<T> x = ad::batched_solve(inputs[0], inputs[1]);
      ad::grad_into(ad::sum(ad::square(x)), inputs, first, {.create_graph = true});
      ad::grad_into(ad::sum(ad::square(first[0])) + ad::sum(ad::square(first[1])), inputs,
                    second);
    }
    if (step >= warmup) counted += g_allocations.load() - before;
  }
  return counted;
}

TEST(BatchedAllocations, SolveAndItsDerivativesAllocateNothingAfterWarmUp) {
#ifndef HNN_COUNT_ALLOCATIONS
  GTEST_SKIP() << "malloc belongs to the sanitizer in this build";
#else
  for (Eigen::Index n : {2, 4}) {
    EXPECT_EQ(AllocationsOfSolveSteps<double>(512, n, 3, 10), 0) << "double, n " << n;
    EXPECT_EQ(AllocationsOfSolveSteps<float>(512, n, 3, 10), 0) << "float, n " << n;
  }
#endif
}

TEST(BatchedAllocations, TheCounterSeesAllocations) {
#ifndef HNN_COUNT_ALLOCATIONS
  GTEST_SKIP() << "malloc belongs to the sanitizer in this build";
#else
  const long before = g_allocations.load();
  auto* v = new std::vector<double>(1000);
  const long after = g_allocations.load();
  delete v;
  EXPECT_GE(after - before, 2);  // the vector object and its buffer
#endif
}

}  // namespace
