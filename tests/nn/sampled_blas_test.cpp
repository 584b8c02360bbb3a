// The dense kernels of the sampled fit's ridge solver (nn/sampled/blas.h) against Eigen's own
// decompositions on small matrices.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "nn/sampled/blas.h"

namespace hnn::nn::sampled {
namespace {

ColMat random_triangle(Eigen::Index n) {
  ColMat r = ColMat::Random(n, n).triangularView<Eigen::Upper>();
  r.diagonal().array() += 3.0;  // well conditioned: the normal equations are exact enough
  return r;
}

// min |R x - b|^2 + mu^2 |x|^2 is the solution of (R^T R + mu^2 I) x = R^T b.
TEST(SampledBlas, RidgeTriangleSolvesTheRegularisedNormalEquations) {
  const Eigen::Index n = 30;
  for (double mu : {0.0, 0.5, 4.0}) {
    ColMat r = random_triangle(n), b = ColMat::Random(n, 2);
    const ColMat normal = r.transpose() * r + mu * mu * ColMat::Identity(n, n);
    const ColMat want = normal.llt().solve(r.transpose() * b);
    ridge_triangle(r, b, mu);
    EXPECT_LT((b - want).norm(), 1e-12 * want.norm()) << "mu " << mu;
  }
}

// Power steps approach it from below, the faster the wider the gap to the second: one large
// diagonal entry makes the gap whatever the random draw (a random triangle alone had a gap so
// narrow in some draws that 200 steps were 2e-3 short).
TEST(SampledBlas, LargestSingularValueOfATriangle) {
  ColMat r = random_triangle(40);
  r(0, 0) += 20.0;
  const double want = Eigen::JacobiSVD<ColMat>(r).singularValues()(0);
  EXPECT_LE(largest_singular_value(r), want * (1 + 1e-12));
  EXPECT_GT(largest_singular_value(r), 0.9 * want);
  EXPECT_NEAR(largest_singular_value(r, 200), want, 1e-3 * want);
  EXPECT_EQ(largest_singular_value(ColMat::Zero(3, 3)), 0.0);
}

// A tall matrix becomes its QR's triangle with Q^T b's head; a triangle is left as it is.
TEST(SampledBlas, ReduceToTriangleKeepsTheLeastSquaresSolution) {
  const ColMat a0 = ColMat::Random(50, 8), b0 = ColMat::Random(50, 1);
  ColMat a = a0, b = b0;
  reduce_to_triangle(a, b);
  ASSERT_EQ(a.rows(), 8);
  ASSERT_EQ(b.rows(), 8);
  const ColMat want = a0.colPivHouseholderQr().solve(b0);
  EXPECT_LT((a.triangularView<Eigen::Upper>().solve(b) - want).norm(), 1e-12 * want.norm());
  const ColMat t = random_triangle(6), tb = ColMat::Random(6, 1);
  ColMat t2 = t, tb2 = tb;
  reduce_to_triangle(t2, tb2);
  EXPECT_EQ(t2, t);
  EXPECT_EQ(tb2, tb);
}

}  // namespace
}  // namespace hnn::nn::sampled
