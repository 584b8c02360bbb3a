// batched_solve, batched_matvec and batched_outer: derivatives against finite differences to
// first, second and (for the solve) third order; the solve against Eigen block by block; the
// guard that refuses singular, ill-conditioned and non-finite blocks by row; shape errors.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "autodiff/autodiff.h"
#include "test_util.h"

namespace ad = hnn::ad;
using ad::Var;
using ad::testing::MatrixD;
using ad::testing::random_matrix;
using VarD = Var<double>;
using Inputs = std::vector<VarD>;

namespace {

// R blocks n x n, one per row: the identity times 2 plus entries in [-0.5, 0.5), so every
// block is diagonally dominant enough to be well conditioned (for n <= 4).
MatrixD WellConditionedBlocks(Eigen::Index rows, Eigen::Index n, unsigned seed) {
  MatrixD a = random_matrix(rows, n * n, seed, -0.5, 0.5);
  for (Eigen::Index r = 0; r < rows; ++r)
    for (Eigen::Index i = 0; i < n; ++i) a(r, i * n + i) += 2.0;
  return a;
}

Eigen::MatrixXd Block(const MatrixD& a, Eigen::Index r, Eigen::Index n) {
  return a.row(r).reshaped<Eigen::RowMajor>(n, n);
}

// The message of the ad::Error that f throws ("" when it throws none).
std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ad::Error& e) {
    return e.what();
  }
  return "";
}

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

struct BatchedCase {
  std::string name;
  std::function<VarD(const Inputs&)> f;
  std::vector<MatrixD> inputs;
};

void PrintTo(const BatchedCase& c, std::ostream* os) { *os << c.name; }

std::vector<BatchedCase> AllCases() {
  std::vector<BatchedCase> cases;
  for (Eigen::Index n : {1, 2, 3}) {
    for (bool t : {false, true}) {
      const std::string suffix = std::to_string(n) + (t ? "_transposed" : "");
      cases.push_back({"Solve_n" + suffix,
                       [t](const Inputs& in) { return ad::batched_solve(in[0], in[1], t); },
                       {WellConditionedBlocks(3, n, 10 + n), random_matrix(3, n, 20 + n)}});
      cases.push_back({"Matvec_n" + suffix,
                       [t](const Inputs& in) { return ad::batched_matvec(in[0], in[1], t); },
                       {random_matrix(3, n * n, 30 + n), random_matrix(3, n, 40 + n)}});
    }
  }
  // Rectangular blocks: 2 x 3 times a 3-vector, and 3 x 2 used transposed.
  cases.push_back({"Matvec_rectangular",
                   [](const Inputs& in) { return ad::batched_matvec(in[0], in[1]); },
                   {random_matrix(3, 6, 50), random_matrix(3, 3, 51)}});
  cases.push_back({"Matvec_rectangular_transposed",
                   [](const Inputs& in) { return ad::batched_matvec(in[0], in[1], true); },
                   {random_matrix(3, 6, 52), random_matrix(3, 3, 53)}});
  cases.push_back({"Outer_3x2",
                   [](const Inputs& in) { return ad::batched_outer(in[0], in[1]); },
                   {random_matrix(3, 3, 60), random_matrix(3, 2, 61)}});
  cases.push_back({"Outer_1x1",
                   [](const Inputs& in) { return ad::batched_outer(in[0], in[1]); },
                   {random_matrix(4, 1, 62), random_matrix(4, 1, 63)}});
  // A solve whose operands are themselves computed: the chain through both inputs.
  cases.push_back({"Solve_of_outer_plus_identity",
                   [](const Inputs& in) {
                     const VarD a = ad::batched_outer(in[0], in[1]) +
                                    VarD::constant(WellConditionedBlocks(2, 2, 70));
                     return ad::batched_solve(a, ad::tanh(in[2]));
                   },
                   {random_matrix(2, 2, 71, -0.4, 0.4), random_matrix(2, 2, 72, -0.4, 0.4),
                    random_matrix(2, 2, 73)}});
  return cases;
}

class BatchedDerivatives : public ::testing::TestWithParam<BatchedCase> {};

TEST_P(BatchedDerivatives, GradcheckMatchesFiniteDifferences) {
  const ad::CheckResult r = ad::gradcheck(GetParam().f, GetParam().inputs);
  EXPECT_TRUE(r.ok) << r.worst << "\n" << r.log;
}

TEST_P(BatchedDerivatives, GradgradcheckMatchesFiniteDifferences) {
  const ad::CheckResult r = ad::gradgradcheck(GetParam().f, GetParam().inputs);
  EXPECT_TRUE(r.ok) << r.worst << "\n" << r.log;
}

TEST_P(BatchedDerivatives, GradgradcheckOfSinOfOpMatchesFiniteDifferences) {
  // The bilinear ops have constant second derivatives; a nonlinearity on top exercises the
  // second-order terms that multiply the op's own Jacobian.
  const auto f = GetParam().f;
  const ad::CheckResult r =
      ad::gradgradcheck([f](const Inputs& in) { return ad::sin(f(in)); }, GetParam().inputs);
  EXPECT_TRUE(r.ok) << r.worst << "\n" << r.log;
}

INSTANTIATE_TEST_SUITE_P(AllOps, BatchedDerivatives, ::testing::ValuesIn(AllCases()),
                         [](const auto& info) { return info.param.name; });

TEST(BatchedSolve, ThirdDerivativesMatchFiniteDifferencesOfTheSecond) {
  // gradgradcheck of the gradient: d^3 / (da db ...) of sum(sin(x)) through the solve.
  for (bool t : {false, true}) {
    const auto gradient = [t](const Inputs& in) {
      const VarD loss = ad::sum(ad::sin(ad::batched_solve(in[0], in[1], t)));
      return ad::grad<double>({loss}, in, {.create_graph = true});
    };
    const ad::CheckResult r =
        ad::gradgradcheck(gradient, {WellConditionedBlocks(2, 2, 80), random_matrix(2, 2, 81)});
    EXPECT_TRUE(r.ok) << (t ? "transposed: " : "") << r.worst << "\n" << r.log;
  }
}

TEST(BatchedSolve, MatchesEigenBlockByBlock) {
  for (Eigen::Index n : {1, 2, 3, 4, 6}) {
    for (Eigen::Index rows : {1, 513}) {
      for (bool t : {false, true}) {
        ad::TapeScope scope;
        const MatrixD a = WellConditionedBlocks(rows, n, unsigned(100 + n));
        const MatrixD b = random_matrix(rows, n, unsigned(200 + n));
        const MatrixD x = ad::batched_solve(VarD::constant(a), VarD::constant(b), t).value();
        ASSERT_EQ(x.rows(), rows);
        ASSERT_EQ(x.cols(), n);
        for (Eigen::Index r = 0; r < rows; ++r) {
          const Eigen::MatrixXd block =
              t ? Eigen::MatrixXd(Block(a, r, n).transpose()) : Block(a, r, n);
          const Eigen::VectorXd expected = block.fullPivLu().solve(b.row(r).transpose());
          ASSERT_LT((x.row(r).transpose() - expected).norm(), 1e-13 * expected.norm() + 1e-15)
              << "n " << n << ", R " << rows << (t ? ", transposed" : "") << ", row " << r;
        }
      }
    }
  }
}

TEST(BatchedSolve, ResidualIsSmallOnPoorlyScaledButWellConditionedBlocks) {
  // rcond does not depend on scale: blocks of size 1e-200 and 1e200 are solved, not refused.
  for (double s : {1e-200, 1e200}) {
    ad::TapeScope scope;
    const MatrixD a = s * WellConditionedBlocks(4, 3, 5);
    const MatrixD b = random_matrix(4, 3, 6);
    const MatrixD x = ad::batched_solve(VarD::constant(a), VarD::constant(b)).value();
    for (Eigen::Index r = 0; r < 4; ++r) {
      const Eigen::VectorXd residual = Block(a, r, 3) * x.row(r).transpose() - b.row(r).transpose();
      EXPECT_LT(residual.norm(), 1e-14) << "scale " << s << ", row " << r;
    }
  }
}

TEST(BatchedSolve, SingularBlockThrowsNamingItsRow) {
  MatrixD a = WellConditionedBlocks(5, 2, 7);
  a.row(3) << 1, 2, 2, 4;  // rank 1
  const std::string message = ErrorOf([&] {
    ad::TapeScope scope;
    ad::batched_solve(VarD::constant(a), VarD::constant(random_matrix(5, 2, 8)));
  });
  EXPECT_TRUE(Contains(message, "batched_solve: block 3 of 5 is singular or ill-conditioned"))
      << message;
  EXPECT_TRUE(Contains(message, "rcond")) << message;
}

TEST(BatchedSolve, IllConditionedBlockThrowsAndItsEstimateIsReported) {
  MatrixD a = WellConditionedBlocks(3, 2, 9);
  a.row(1) << 1, 1, 1, 1 + 1e-15;  // cond ~ 4e15: rcond ~ 2.5e-16 < 2.2e-14
  const std::string message = ErrorOf([&] {
    ad::TapeScope scope;
    ad::batched_solve(VarD::constant(a), VarD::constant(random_matrix(3, 2, 10)), true);
  });
  EXPECT_TRUE(Contains(message, "block 1 of 3 is singular or ill-conditioned")) << message;
  EXPECT_TRUE(Contains(message, "e-16")) << message;
}

TEST(BatchedSolve, ThresholdIsPerPrecision) {
  // cond ~ 4e5: fine in double, refused in float (100 eps = 1.2e-5 > rcond ~ 2.5e-6).
  MatrixD a(1, 4);
  a << 1, 1, 1, 1 + 1e-5;
  const MatrixD b = random_matrix(1, 2, 11);
  {
    ad::TapeScope scope;
    EXPECT_NO_THROW(ad::batched_solve(VarD::constant(a), VarD::constant(b)));
  }
  const std::string message = ErrorOf([&] {
    ad::TapeScope scope;
    ad::batched_solve(Var<float>::constant(a.cast<float>()), Var<float>::constant(b.cast<float>()));
  });
  EXPECT_TRUE(Contains(message, "block 0 of 1 is singular or ill-conditioned")) << message;
}

TEST(BatchedSolve, NonFiniteBlockOrRightHandSideThrowsNamingItsRow) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  MatrixD a = WellConditionedBlocks(4, 3, 12), b = random_matrix(4, 3, 13);
  a(2, 4) = nan;
  std::string message = ErrorOf([&] {
    ad::TapeScope scope;
    ad::batched_solve(VarD::constant(a), VarD::constant(b));
  });
  EXPECT_TRUE(Contains(message, "batched_solve: block 2 of 4 has a non-finite entry")) << message;

  a(2, 4) = 0.1;
  b(1, 0) = std::numeric_limits<double>::infinity();
  message = ErrorOf([&] {
    ad::TapeScope scope;
    ad::batched_solve(VarD::constant(a), VarD::constant(b));
  });
  EXPECT_TRUE(Contains(message, "right-hand side 1 of 4 has a non-finite entry")) << message;
}

TEST(BatchedSolve, NonFiniteGradientIsCaughtByTheAdjointSolve) {
  // The backward is a solve too: a NaN arriving from upstream is named, not propagated.
  ad::TapeScope scope;
  const VarD a = VarD::leaf(WellConditionedBlocks(3, 2, 14));
  const VarD x = ad::batched_solve(a, VarD::constant(random_matrix(3, 2, 15)));
  MatrixD seed = MatrixD::Ones(3, 2);
  seed(2, 1) = std::numeric_limits<double>::quiet_NaN();
  const std::string message =
      ErrorOf([&] { ad::grad<double>({x}, {a}, {}, {VarD::constant(seed)}); });
  EXPECT_TRUE(Contains(message, "right-hand side 2 of 3 has a non-finite entry")) << message;
}

TEST(BatchedOps, ShapeMismatchesThrowNamingBothShapes) {
  ad::TapeScope scope;
  const VarD a9 = VarD::constant(random_matrix(3, 9, 1));
  const VarD a8 = VarD::constant(random_matrix(3, 8, 2));
  const VarD v3 = VarD::constant(random_matrix(3, 3, 3));
  const VarD v4rows = VarD::constant(random_matrix(4, 3, 4));
  std::string message = ErrorOf([&] { ad::batched_solve(a8, v3); });
  EXPECT_TRUE(Contains(message, "3x8") && Contains(message, "3x3")) << message;
  message = ErrorOf([&] { ad::batched_solve(a9, v4rows); });
  EXPECT_TRUE(Contains(message, "3x9") && Contains(message, "4x3")) << message;
  message = ErrorOf([&] { ad::batched_matvec(a8, v3); });
  EXPECT_TRUE(Contains(message, "3x8") && Contains(message, "3x3")) << message;
  message = ErrorOf([&] { ad::batched_matvec(a9, v4rows, true); });
  EXPECT_TRUE(Contains(message, "3x9") && Contains(message, "4x3")) << message;
  message = ErrorOf([&] { ad::batched_outer(v3, v4rows); });
  EXPECT_TRUE(Contains(message, "3x3") && Contains(message, "4x3")) << message;
}

TEST(BatchedOps, FloatSmokeTest) {
  ad::TapeScope scope;
  const MatrixD a = WellConditionedBlocks(8, 3, 16), b = random_matrix(8, 3, 17);
  const Var<float> af = Var<float>::leaf(a.cast<float>()), bf = Var<float>::leaf(b.cast<float>());
  const Var<float> x = ad::batched_solve(af, bf);
  const Var<float> y = ad::batched_matvec(af, x);  // = b
  EXPECT_LT((y.value().cast<double>() - b).cwiseAbs().maxCoeff(), 1e-5);
  const Var<float> loss = ad::sum(ad::square(ad::batched_outer(x, bf)));
  const std::vector<Var<float>> g = ad::grad<float>({loss}, {af, bf});

  const VarD ad_ = VarD::leaf(a), bd = VarD::leaf(b);
  const VarD loss_d = ad::sum(ad::square(ad::batched_outer(ad::batched_solve(ad_, bd), bd)));
  const std::vector<VarD> gd = ad::grad<double>({loss_d}, {ad_, bd});
  EXPECT_LT(ad::testing::relative_error(g[0].value().cast<double>(), gd[0].value()), 1e-5);
  EXPECT_LT(ad::testing::relative_error(g[1].value().cast<double>(), gd[1].value()), 1e-5);
}

TEST(BatchedOps, MatvecUndoesTheSolveBothWays) {
  ad::TapeScope scope;
  const VarD a = VarD::constant(WellConditionedBlocks(6, 4, 18));
  const VarD b = VarD::constant(random_matrix(6, 4, 19));
  for (bool t : {false, true}) {
    const MatrixD back = ad::batched_matvec(a, ad::batched_solve(a, b, t), t).value();
    EXPECT_LT((back - b.value()).cwiseAbs().maxCoeff(), 1e-14) << (t ? "transposed" : "");
  }
}

}  // namespace
