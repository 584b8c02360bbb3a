// The sketch solver (nn/sampled/sketch.h): its sparse sign embedding keeps a column space's
// norms, and its preconditioned LSQR reaches ridge's solution of the whole problem.

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <random>

#include "autodiff/parallel.h"
#include "nn/sampled/lsqr.h"
#include "nn/sampled/sketch.h"
#include "nn/sampled/sparse_sign.h"
#include "nn/sampled/systems.h"

namespace hnn::nn::sampled {
namespace sketch_test {

using Eigen::Index;

// Each input row lands in kSketchNonzeros distinct output rows at ±1/sqrt(kSketchNonzeros).
TEST(SampledSketch, SparseSignHasItsNonzerosPerRow) {
  const SparseSign s(50, 30, 7);
  const ColMat formed = s.apply(ColMat::Identity(50, 50));  // S itself, 30 x 50
  for (Index i = 0; i < 50; ++i) {
    EXPECT_EQ((formed.col(i).array() != 0).count(), kSketchNonzeros) << "row " << i;
    for (Index r = 0; r < 30; ++r) {
      if (formed(r, i) != 0) {
        EXPECT_DOUBLE_EQ(std::abs(formed(r, i)), 1 / std::sqrt(8.0));
      }
    }
  }
  EXPECT_EQ(formed, SparseSign(50, 30, 7).apply(ColMat::Identity(50, 50)));  // seeded
  EXPECT_NE(formed, SparseSign(50, 30, 8).apply(ColMat::Identity(50, 50)));
}

// A subspace embedding: with twice the subspace's dimension in rows, S Q (Q an orthonormal
// basis) has singular values within the distortion sqrt(d / s) ~ 0.7 of 1, which is what bounds
// the preconditioned condition number, and so LSQR's iterations.
TEST(SampledSketch, SparseSignEmbedsAColumnSpace) {
  const Index n = 4000, d = 50;
  const ColMat q =
      Eigen::HouseholderQR<ColMat>(ColMat::Random(n, d)).householderQ() * ColMat::Identity(n, d);
  const Eigen::VectorXd sv =
      Eigen::JacobiSVD<ColMat>(SparseSign(n, 2 * d, 3).apply(q)).singularValues();
  EXPECT_GT(sv.minCoeff(), 0.2);
  EXPECT_LT(sv.maxCoeff(), 1.8);
}

TEST(SampledSketch, SparseSignGivesTheSameBitsAtAnyThreadCount) {
  const ColMat x = ColMat::Random(3000, 40);
  const int threads = ad::num_threads();
  ad::set_num_threads(1);
  const ColMat one = SparseSign(3000, 80, 5).apply(x);
  ad::set_num_threads(2);
  const ColMat two = SparseSign(3000, 80, 5).apply(x);
  ad::set_num_threads(threads);
  EXPECT_EQ(one, two);
}

// Sampled-like features: tanh'(x w + b) of steep and flat neurons over 1-D points, numerically
// dependent (the ridge damping is what makes the problem solvable).
ColMat features(Index n, Index w, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), slope(0.1, 20);
  Eigen::VectorXd x(n);
  for (Index i = 0; i < n; ++i) x(i) = u(rng);
  ColMat d(n, w);
  for (Index k = 0; k < w; ++k) {
    const double a = slope(rng), b = u(rng) * a;
    d.col(k) = (x.array() * a + b).tanh().square().unaryExpr([](double t) { return 1 - t; });
  }
  return d;
}

// ridge's solution of the whole problem at mu: QR of A's reduction, then Tikhonov.
ColMat ridge_solution(const LinearSystem& system, double mu) {
  ColMat r, b;
  system.reduced(r, b);
  reduce_to_triangle(r, b);
  ridge_triangle(r, b, mu);
  return b;
}

// On every form (an HNN's Hadamard system of one and of two column blocks, a formed baseline
// matrix) the sketch's LSQR converges to ridge's solution at the same mu in few iterations.
TEST(SampledSketch, ReachesRidgesSolution) {
  const Index n = 3000, w = 40, dim = 4;
  const ColMat d = features(n, w, 1), targets = ColMat::Random(n, dim);
  std::vector<std::unique_ptr<LinearSystem>> systems;
  for (int blocks : {1, 2}) {
    systems.push_back(
        std::make_unique<HadamardSystem>(d, ColMat::Random(dim, blocks * w), targets));
  }
  systems.push_back(std::make_unique<DenseSystem>(d, targets));
  for (const auto& system : systems) {
    ASSERT_GT(system->sketch_rows(), kSketchRowsPerUnknown * double(system->unknowns()));
    const SketchedRidge sketch(*system, 11);
    for (double rcond : {1e-12, 1e-6}) {
      const SketchedRidge::Solution got = sketch.solve(rcond, 1e-14, 200);
      const ColMat want = ridge_solution(*system, rcond * sketch.largest());
      EXPECT_LT((got.c - want).norm(), 1e-6 * want.norm())
          << system->unknowns() << " unknowns, rcond " << rcond;
      EXPECT_LT(got.iterations, 60) << system->unknowns() << " unknowns, rcond " << rcond;
      ColMat fit_got(system->equations(), system->rhs_columns()), fit_want = fit_got;
      system->apply(got.c, fit_got);
      system->apply(want, fit_want);
      EXPECT_LT((fit_got - fit_want).norm(), 1e-9 * system->rhs().norm());
    }
  }
}

// Without more rows than the sketch would have, the system's own reduction preconditions
// exactly: LSQR has nothing left to do.
TEST(SampledSketch, FewRowsPreconditionExactly) {
  const HadamardSystem system(features(60, 40, 2), ColMat::Random(2, 40), ColMat::Random(60, 2));
  const SketchedRidge sketch(system, 1);
  const SketchedRidge::Solution got = sketch.solve(1e-10, 1e-14, 200);
  EXPECT_LE(got.iterations, 3);
  const ColMat want = ridge_solution(system, 1e-10 * sketch.largest());
  EXPECT_LT((got.c - want).norm(), 1e-8 * want.norm());
}

}  // namespace sketch_test
}  // namespace hnn::nn::sampled
