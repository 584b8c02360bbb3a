// batched_spd_solve: the solution against Eigen's Cholesky block by block, its derivatives
// against finite differences to second order (also for blocks that are not symmetric, of which
// it reads the symmetric part), and the errors that name the row of a block it cannot solve.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <limits>
#include <string>
#include <vector>

#include "autodiff/autodiff.h"
#include "test_util.h"

namespace ad = hnn::ad;
using ad::Var;
using ad::testing::MatrixD;
using ad::testing::random_matrix;

namespace spd_solve_test {

// R symmetric positive definite blocks B B^T + I / 2, one per row, flattened row-major.
MatrixD SpdBlocks(Eigen::Index rows, Eigen::Index n, unsigned seed) {
  const MatrixD b = random_matrix(rows, n * n, seed);
  MatrixD a(rows, n * n);
  for (Eigen::Index r = 0; r < rows; ++r) {
    const Eigen::MatrixXd factor = b.row(r).reshaped<Eigen::RowMajor>(n, n);
    const Eigen::MatrixXd block =
        factor * factor.transpose() + 0.5 * Eigen::MatrixXd::Identity(n, n);
    a.row(r) = block.reshaped<Eigen::RowMajor>().transpose();
  }
  return a;
}

std::string ErrorOf(const MatrixD& a, const MatrixD& b) {
  try {
    ad::TapeScope scope;
    ad::batched_spd_solve(Var<double>::constant(a), Var<double>::constant(b));
  } catch (const ad::Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace spd_solve_test

using spd_solve_test::SpdBlocks;

TEST(BatchedSpdSolve, MatchesEigensCholeskyPerRow) {
  for (Eigen::Index n : {1, 3, 6}) {
    const MatrixD a = SpdBlocks(5, n, 1), b = random_matrix(5, n, 2);
    ad::TapeScope scope;
    const MatrixD x =
        ad::batched_spd_solve(Var<double>::constant(a), Var<double>::constant(b)).value();
    for (Eigen::Index r = 0; r < 5; ++r) {
      const Eigen::MatrixXd block = a.row(r).reshaped<Eigen::RowMajor>(n, n);
      const Eigen::VectorXd want = block.llt().solve(b.row(r).transpose());
      EXPECT_LT((x.row(r).transpose() - want).norm(), 1e-12 * (1 + want.norm())) << n << " " << r;
    }
  }
}

TEST(BatchedSpdSolve, DerivativesMatchFiniteDifferencesToSecondOrder) {
  for (Eigen::Index n : {1, 2, 3}) {
    // A nonsymmetric perturbation of SPD blocks: the op reads (A + A^T) / 2, and its gradient
    // must be the derivative of exactly that.
    const MatrixD a = SpdBlocks(3, n, 3) + 0.1 * random_matrix(3, n * n, 4);
    const auto f = [](const std::vector<Var<double>>& in) {
      return ad::sum(ad::sin(ad::batched_spd_solve(in[0], in[1])));
    };
    const std::vector<MatrixD> inputs{a, random_matrix(3, n, 5)};
    const ad::CheckResult first = ad::gradcheck(f, inputs);
    EXPECT_TRUE(first.ok) << n << ": " << first.worst << "\n" << first.log;
    const ad::CheckResult second = ad::gradgradcheck(f, inputs);
    EXPECT_TRUE(second.ok) << n << ": " << second.worst << "\n" << second.log;
  }
}

TEST(BatchedSpdSolve, FloatAgreesWithDouble) {
  const MatrixD a = SpdBlocks(4, 3, 6), b = random_matrix(4, 3, 7);
  ad::TapeScope scope;
  const MatrixD xd =
      ad::batched_spd_solve(Var<double>::constant(a), Var<double>::constant(b)).value();
  const ad::Matrix<float> xf = ad::batched_spd_solve(Var<float>::constant(a.cast<float>()),
                                                     Var<float>::constant(b.cast<float>()))
                                   .value();
  EXPECT_LT((xf.cast<double>() - xd).cwiseAbs().maxCoeff(), 1e-4 * (1 + xd.cwiseAbs().maxCoeff()));
}

TEST(BatchedSpdSolve, NamesTheRowOfABlockItCannotSolve) {
  MatrixD a = SpdBlocks(4, 2, 8);
  const MatrixD b = random_matrix(4, 2, 9);
  a.row(2) << 1, 0, 0, -1;  // indefinite
  EXPECT_NE(spd_solve_test::ErrorOf(a, b).find(
                "batched_spd_solve: block 2 of 4 is not positive definite"),
            std::string::npos)
      << spd_solve_test::ErrorOf(a, b);
  a.row(2) << 1, 0, 0, 1e-15;  // positive, but no digits left
  EXPECT_NE(spd_solve_test::ErrorOf(a, b).find("block 2 of 4 is ill-conditioned"),
            std::string::npos)
      << spd_solve_test::ErrorOf(a, b);
  a.row(2) << 1, 0, 0, std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(spd_solve_test::ErrorOf(a, b).find("block 2 of 4 has a non-finite entry"),
            std::string::npos);
  MatrixD bad_rhs = b;
  bad_rhs(1, 0) = std::numeric_limits<double>::infinity();
  EXPECT_NE(spd_solve_test::ErrorOf(SpdBlocks(4, 2, 8), bad_rhs)
                .find("right-hand side 1 of 4 has a non-finite entry"),
            std::string::npos);
  EXPECT_NE(spd_solve_test::ErrorOf(SpdBlocks(4, 2, 8), random_matrix(4, 3, 10))
                .find("do not match right-hand sides"),
            std::string::npos);
}
