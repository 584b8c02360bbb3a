// A recorded batched_solve and its backward (first and second order) allocate nothing on the
// heap once warmed up inside a reused TapeScope: the LU works in fixed-size storage for blocks up
// to 4x4 and every node's buffer is recycled. batched_spd_solve likewise, at any block size (its
// Cholesky works in the node's recycled buffers). Counted by tests/malloc_counter.cpp, linked into
// the autodiff test program.

#include <gtest/gtest.h>

#include <cstdlib>
#include <vector>

#include "autodiff/autodiff.h"
#include "malloc_counter.h"
#include "test_util.h"

namespace ad = hnn::ad;
using ad::Var;
using ad::testing::MatrixD;

namespace {

// batched_spd_solve at its default least rcond.
template <typename T>
Var<T> SpdSolve(const Var<T>& a, const Var<T>& b) {
  return ad::batched_spd_solve(a, b);
}

// Heap allocations of `steps` steps after `warmup`: x = solve(A, b), loss = sum(x^2), its
// gradient with create_graph, and the gradient of |grad|^2 (the backward's own backward).
template <typename T, typename Solve = Var<T> (*)(const Var<T>&, const Var<T>&)>
long AllocationsOfSolveSteps(
    Eigen::Index rows, Eigen::Index n, int warmup, int steps,
    Solve solve = [](const Var<T>& a, const Var<T>& b) { return ad::batched_solve(a, b); }) {
  MatrixD a = ad::testing::random_matrix(rows, n * n, 1, -0.5, 0.5);
  for (Eigen::Index r = 0; r < rows; ++r)
    for (Eigen::Index i = 0; i < n; ++i) a(r, i * n + i) += 2.0;
  const std::vector<Var<T>> inputs = {
      Var<T>::leaf(a.cast<T>()), Var<T>::leaf(ad::testing::random_matrix(rows, n, 2).cast<T>())};
  std::vector<Var<T>> first, second;
  long counted = 0;
  for (int step = 0; step < warmup + steps; ++step) {
    const long before = hnn::testing::allocation_count();
    {
      ad::TapeScope scope;
      const Var<T> x = solve(inputs[0], inputs[1]);
      ad::grad_into(ad::sum(ad::square(x)), inputs, first, {.create_graph = true});
      ad::grad_into(ad::sum(ad::square(first[0])) + ad::sum(ad::square(first[1])), inputs, second);
    }
    if (step >= warmup) counted += hnn::testing::allocation_count() - before;
  }
  return counted;
}

TEST(BatchedAllocations, SolveAndItsDerivativesAllocateNothingAfterWarmUp) {
#if !HNN_COUNTS_ALLOCATIONS
  GTEST_SKIP() << "malloc belongs to the sanitizer in this build";
#else
  for (Eigen::Index n : {2, 4}) {
    EXPECT_EQ(AllocationsOfSolveSteps<double>(512, n, 3, 10), 0) << "double, n " << n;
    EXPECT_EQ(AllocationsOfSolveSteps<float>(512, n, 3, 10), 0) << "float, n " << n;
  }
#endif
}

TEST(BatchedAllocations, SpdSolveAndItsDerivativesAllocateNothingAfterWarmUpAtAnySize) {
#if !HNN_COUNTS_ALLOCATIONS
  GTEST_SKIP() << "malloc belongs to the sanitizer in this build";
#else
  for (Eigen::Index n : {2, 5}) {  // above 4, where batched_solve's LU allocates
    EXPECT_EQ(AllocationsOfSolveSteps<double>(256, n, 3, 10, SpdSolve<double>), 0)
        << "double, n " << n;
    EXPECT_EQ(AllocationsOfSolveSteps<float>(256, n, 3, 10, SpdSolve<float>), 0)
        << "float, n " << n;
  }
#endif
}

// Heap allocations of `steps` steps after `warmup` of an LNN-shaped third-order path: a batch
// as a tape variable, its per-row Hessian blocks by row_jacobian of a recorded gradient, the
// parameter gradient through all of it.
template <typename T>
long AllocationsOfRowJacobianSteps(int warmup, int steps) {
  const ad::Matrix<T> x0 = ad::testing::random_matrix(64, 4, 3).cast<T>();
  const Var<T> w = Var<T>::leaf(ad::testing::random_matrix(4, 8, 4).cast<T>());
  const std::vector<Var<T>> params = {w};
  std::vector<Var<T>> grads;
  long counted = 0;
  for (int step = 0; step < warmup + steps; ++step) {
    const long before = hnn::testing::allocation_count();
    {
      ad::TapeScope scope;
      const Var<T> x = Var<T>::variable(x0);
      const Var<T> l = ad::sum_cols(ad::softplus(ad::matmul(x, w)));
      const Var<T> blocks = ad::row_hessian(l, x, {.create_graph = true});
      ad::grad_into(ad::sum(ad::square(blocks)), params, grads);
    }
    if (step >= warmup) counted += hnn::testing::allocation_count() - before;
  }
  return counted;
}

TEST(BatchedAllocations, RowJacobianOfAVariableAllocatesNothingAfterWarmUp) {
#if !HNN_COUNTS_ALLOCATIONS
  GTEST_SKIP() << "malloc belongs to the sanitizer in this build";
#else
  EXPECT_EQ(AllocationsOfRowJacobianSteps<double>(3, 10), 0);
  EXPECT_EQ(AllocationsOfRowJacobianSteps<float>(3, 10), 0);
#endif
}

TEST(BatchedAllocations, TheCounterSeesAllocations) {
#if !HNN_COUNTS_ALLOCATIONS
  GTEST_SKIP() << "malloc belongs to the sanitizer in this build";
#else
  const long before = hnn::testing::allocation_count();
  std::vector<double>* volatile v = new std::vector<double>(1000);  // volatile: not elided
  const long after = hnn::testing::allocation_count();
  delete v;
  EXPECT_GE(after - before, 2);  // the vector object and its buffer
#endif
}

}  // namespace
