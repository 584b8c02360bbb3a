// The fused kernels' matrix product (autodiff/gemm.h): every transpose, every remainder of the
// AVX-512 kernel's tiles, panels and depth blocks, on blocks of larger matrices; and the kernel's
// promise that an element's sum runs down the shared dimension in order, whatever the shape.

#include "autodiff/gemm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

#include "test_util.h"

namespace ad = hnn::ad;
using ad::testing::random_matrix;
using Index = Eigen::Index;

namespace {

template <typename T>
using RowMatrix = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Row counts around the kernel's tile height (14), column counts around its panel widths (16
// doubles, 32 floats; a last panel of one vector takes a one-vector tile: 31, 62 and 200 leave
// lanes empty), depths around its depth block (128), and none (C = beta C).
constexpr Index kRowCounts[] = {2, 13, 15, 29, 100};
constexpr Index kColumnCounts[] = {16, 31, 62, 64, 200};
constexpr Index kDepths[] = {0, 1, 5, 128, 129, 300};

// op(M) stored as a block of a larger matrix with a margin, so that strides differ from widths.
template <typename T>
RowMatrix<T> stored(Index rows, Index cols, bool transposed, unsigned seed) {
  return random_matrix(transposed ? cols : rows, transposed ? rows : cols, seed).cast<T>();
}

template <typename T>
void expect_products_match_double_products() {
  const T tolerance = std::is_same_v<T, float> ? T(2e-5) : T(1e-13);
  for (const bool ta : {false, true}) {
    for (const bool tb : {false, true}) {
      for (const Index m : kRowCounts) {
        for (const Index n : kColumnCounts) {
          for (const Index k : kDepths) {
            for (const T beta : {T(0), T(1)}) {
              const RowMatrix<T> a_store = stored<T>(m + 3, k + 5, ta, 1);
              const RowMatrix<T> b_store = stored<T>(k + 4, n + 7, tb, 2);
              RowMatrix<T> c_store = random_matrix(m + 4, n + 6, 3).cast<T>();
              const RowMatrix<T> before = c_store;
              const auto a = ta ? a_store.block(1, 2, k, m) : a_store.block(1, 2, m, k);
              const auto b = tb ? b_store.block(1, 3, n, k) : b_store.block(1, 3, k, n);
              ad::detail::gemm(a, ta, b, tb, c_store.block(2, 1, m, n), beta);

              Eigen::MatrixXd op_a = a.template cast<double>();
              Eigen::MatrixXd op_b = b.template cast<double>();
              if (ta) op_a.transposeInPlace();
              if (tb) op_b.transposeInPlace();
              Eigen::MatrixXd expected = before.template cast<double>();
              expected.block(2, 1, m, n) = op_a * op_b + double(beta) * expected.block(2, 1, m, n);
              const double scale = 1 + std::sqrt(double(k));
              const double error =
                  (c_store.template cast<double>() - expected).cwiseAbs().maxCoeff();
              EXPECT_LE(error, tolerance * scale)
                  << "ta " << ta << " tb " << tb << " m " << m << " n " << n << " k " << k
                  << " beta " << beta << " (every element outside the block must be untouched)";
            }
          }
        }
      }
    }
  }
}

TEST(Gemm, EveryTransposeShapeAndBetaMatchesTheProductInDouble) {
  expect_products_match_double_products<float>();
  expect_products_match_double_products<double>();
}

// The kernel's element (i, j) is one chain of fused multiply-adds down p = 0..k-1, from 0 or
// from C: so a row block of a product has the same bits as the rows of the whole product, and
// results cannot depend on how the engine's threads split a batch. 62 columns end on a
// two-vector panel, 232 on a one-vector one.
template <typename T>
void expect_each_element_summed_in_order() {
#ifndef __AVX512F__
  GTEST_SKIP() << "this build has no AVX-512 GEMM kernel";
#endif
  for (const bool ta : {false, true}) {
    for (const bool tb : {false, true}) {
      for (const Index n : {62, 232}) {
        const Index m = 29, k = 300;
        const RowMatrix<T> a = stored<T>(m, k, ta, 4), b = stored<T>(k, n, tb, 5);
        RowMatrix<T> c = random_matrix(m, n, 6).cast<T>();
        RowMatrix<T> expected = c;
        const ad::detail::GemmOperands<T> g{m,        n,        k,  a.data(), a.cols(), ta,
                                            b.data(), b.cols(), tb, c.data(), c.cols(), T(1)};
        ASSERT_TRUE(ad::detail::simd_gemm(g)) << "the kernel declined n " << n;
        for (Index i = 0; i < m; ++i) {
          for (Index j = 0; j < n; ++j) {
            T sum = expected(i, j);
            for (Index p = 0; p < k; ++p) {
              sum = std::fma(ta ? a(p, i) : a(i, p), tb ? b(j, p) : b(p, j), sum);
            }
            expected(i, j) = sum;
          }
        }
        EXPECT_EQ(c, expected) << "ta " << ta << " tb " << tb << " n " << n;
      }
    }
  }
}

TEST(Gemm, TheAvx512KernelSumsEachElementDownTheSharedDimensionInOrder) {
  expect_each_element_summed_in_order<float>();
  expect_each_element_summed_in_order<double>();
}

}  // namespace
