// batched_spd_solve: the solution against Eigen's Cholesky block by block, its derivatives
// against finite differences to second order (also for blocks that are not symmetric, of which
// it reads the symmetric part), the errors that name the row of a block it cannot solve, the
// same bits on one thread and two, and batched_spd_solve_factored, which reuses a solve's
// factors for another right-hand side.

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

// A float block at rcond 1e-6 lies below the engine's 100 epsilons (1.2e-5) but above one
// (1.2e-7): refused by default, solved when the caller lowers the minimum to an epsilon (as the
// mass HNN's momentum solve does), and refused again, naming that minimum, below it.
TEST(BatchedSpdSolve, ACallerMayLowerTheLeastConditionItSolvesAt) {
  const double eps = std::numeric_limits<float>::epsilon();
  ad::Matrix<float> a(1, 4), b(1, 2);
  a << 1, 0, 0, 1e-6f;
  b << 2, 3e-6f;
  const auto solve = [&](double min_rcond) {
    ad::TapeScope scope;
    return ad::batched_spd_solve(Var<float>::constant(a), Var<float>::constant(b), min_rcond)
        .value();
  };
  const auto error_of = [&](double min_rcond) -> std::string {
    try {
      solve(min_rcond);
    } catch (const ad::Error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of(100 * eps).find("block 0 of 1 is ill-conditioned (rcond 1e-06, below the "
                                     "minimum 1.19e-05"),
            std::string::npos)
      << error_of(100 * eps);
  const ad::Matrix<float> x = solve(eps);
  EXPECT_NEAR(x(0, 0), 2.0, 1e-6);
  EXPECT_NEAR(x(0, 1), 3.0, 3.0 * eps / 1e-6);
  a(0, 3) = 1e-8f;
  EXPECT_NE(error_of(eps).find("(rcond 1e-08, below the minimum 1.19e-07"), std::string::npos)
      << error_of(eps);
}

TEST(BatchedSpdSolve, GivesTheSameBitsOnOneThreadAndTwo) {
  const MatrixD a = SpdBlocks(300, 3, 11), b = random_matrix(300, 3, 12);
  const auto solve = [&](int threads) {
    ad::set_num_threads(threads);
    ad::TapeScope scope;
    const MatrixD x =
        ad::batched_spd_solve(Var<double>::constant(a), Var<double>::constant(b)).value();
    ad::set_num_threads(2);
    return x;
  };
  EXPECT_TRUE(solve(1) == solve(2));
}

// Constrained mechanics' pattern: a second solve of the same blocks whose right-hand side
// depends on the first solution.
TEST(BatchedSpdSolveFactored, EqualsAFreshSolveAndDifferentiatesToSecondOrder) {
  for (Eigen::Index n : {1, 2, 3}) {
    const MatrixD a = SpdBlocks(3, n, 13) + 0.1 * random_matrix(3, n * n, 14);
    const MatrixD b1 = random_matrix(3, n, 15), b2 = random_matrix(3, n, 16);
    {
      ad::TapeScope scope;
      const Var<double> av = Var<double>::constant(a);
      const Var<double> first = ad::batched_spd_solve(av, Var<double>::constant(b1));
      const Var<double> rhs = Var<double>::constant(b2);
      EXPECT_TRUE(ad::batched_spd_solve_factored(av, rhs, first).value() ==
                  ad::batched_spd_solve(av, rhs).value())
          << n;
    }
    const auto f = [](const std::vector<Var<double>>& in) {
      const Var<double> first = ad::batched_spd_solve(in[0], in[1]);
      return ad::sum(ad::sin(ad::batched_spd_solve_factored(in[0], in[2] * first, first)));
    };
    const std::vector<MatrixD> inputs{a, b1, b2};
    const ad::CheckResult first = ad::gradcheck(f, inputs);
    EXPECT_TRUE(first.ok) << n << ": " << first.worst << "\n" << first.log;
    const ad::CheckResult second = ad::gradgradcheck(f, inputs);
    EXPECT_TRUE(second.ok) << n << ": " << second.worst << "\n" << second.log;
  }
}

TEST(BatchedSpdSolveFactored, RefusesTheFactorsOfAnotherMatrix) {
  ad::TapeScope scope;
  const Var<double> a = Var<double>::constant(SpdBlocks(4, 2, 17));
  const Var<double> other = Var<double>::constant(SpdBlocks(4, 2, 18));
  const Var<double> b = Var<double>::constant(random_matrix(4, 2, 19));
  const Var<double> solved = ad::batched_spd_solve(other, b);
  try {
    ad::batched_spd_solve_factored(a, b, solved);
    FAIL() << "no error";
  } catch (const ad::Error& e) {
    EXPECT_NE(std::string(e.what()).find("did not solve with this matrix"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ad::batched_spd_solve_factored(a, b, b), ad::Error);  // not a solve at all
}
