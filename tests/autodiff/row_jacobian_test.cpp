// row_jacobian and row_hessian against ad::jacobian and ad::hessian of each row on its own,
// differentiated again (third and fourth derivatives of a tanh/softplus MLP against finite
// differences), what they compute when rows are coupled, and the Lagrangian network's
// acceleration M^-1 (dL/dq - C qdot) built from them with batched_solve.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <functional>
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

// An MLP whose hidden layers alternate tanh and softplus (both smooth, so every derivative is
// a fair test); params as ad::testing::mlp_parameters makes them.
VarD SmoothMlp(const std::vector<VarD>& params, VarD x) {
  for (std::size_t l = 0; l + 2 < params.size(); l += 2) {
    const VarD z = ad::linear(x, params[l], params[l + 1]);
    x = (l / 2) % 2 == 0 ? ad::tanh(z) : ad::softplus(z);
  }
  return ad::linear(x, params[params.size() - 2], params.back());
}

// f applied to a single row, for ad::jacobian and ad::hessian.
std::function<VarD(const VarD&)> OnParams(const std::vector<MatrixD>& params) {
  return [params](const VarD& x) { return SmoothMlp(ad::testing::as_leaves<double>(params), x); };
}

TEST(RowJacobian, MatchesTheJacobianOfEachRowAlone) {
  const std::vector<MatrixD> params = ad::testing::mlp_parameters({3, 6, 2}, 1);
  const MatrixD x0 = random_matrix(5, 3, 2);
  ad::TapeScope scope;
  const VarD x = VarD::leaf(x0);
  const MatrixD rows = ad::row_jacobian(OnParams(params)(x), x).value();
  ASSERT_EQ(rows.rows(), 5);
  ASSERT_EQ(rows.cols(), 2 * 3);
  for (Eigen::Index r = 0; r < 5; ++r) {
    const MatrixD expected = ad::jacobian<double>(OnParams(params), x0.row(r));  // 2 x 3
    EXPECT_LT((rows.row(r) - expected.reshaped<Eigen::RowMajor>().transpose()).norm(), 1e-14)
        << "row " << r;
  }
}

TEST(RowHessian, MatchesTheHessianOfEachRowAlone) {
  const std::vector<MatrixD> params = ad::testing::mlp_parameters({4, 8, 8, 1}, 3);
  const MatrixD x0 = random_matrix(6, 4, 4);
  ad::TapeScope scope;
  const VarD x = VarD::leaf(x0);
  const MatrixD blocks = ad::row_hessian(OnParams(params)(x), x).value();
  ASSERT_EQ(blocks.rows(), 6);
  ASSERT_EQ(blocks.cols(), 16);
  for (Eigen::Index r = 0; r < 6; ++r) {
    const MatrixD expected = ad::hessian<double>(OnParams(params), x0.row(r));
    EXPECT_LT((blocks.row(r) - expected.reshaped<Eigen::RowMajor>().transpose()).norm(), 1e-14)
        << "row " << r;
  }
}

TEST(RowHessian, WithoutCreateGraphTheResultIsAConstant) {
  const std::vector<MatrixD> params = ad::testing::mlp_parameters({2, 4, 1}, 5);
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(3, 2, 6));
  EXPECT_FALSE(ad::row_hessian(OnParams(params)(x), x).requires_grad());
  EXPECT_TRUE(ad::row_hessian(OnParams(params)(x), x, {.create_graph = true}).requires_grad());
}

TEST(RowHessian, ThirdDerivativesMatchFiniteDifferencesOfTheHessian) {
  // gradcheck of (x, params) -> row_hessian: the Jacobian of the second-order result, by
  // autodiff (third derivatives of L) against central differences of the Hessian blocks.
  const std::vector<MatrixD> params = ad::testing::mlp_parameters({4, 6, 6, 1}, 7);
  std::vector<MatrixD> inputs = {random_matrix(2, 4, 8)};
  inputs.insert(inputs.end(), params.begin(), params.end());
  const auto hessian_blocks = [](const Inputs& in) {
    const std::vector<VarD> p(in.begin() + 1, in.end());
    return ad::row_hessian(SmoothMlp(p, in[0]), in[0], {.create_graph = true});
  };
  const ad::CheckResult r = ad::gradcheck(hessian_blocks, inputs);
  EXPECT_TRUE(r.ok) << r.worst << "\n" << r.log;
}

TEST(RowHessian, FourthDerivativesMatchFiniteDifferences) {
  const std::vector<MatrixD> params = ad::testing::mlp_parameters({3, 5, 1}, 9);
  const auto hessian_blocks = [&params](const Inputs& in) {
    return ad::row_hessian(SmoothMlp(ad::testing::as_leaves<double>(params), in[0]), in[0],
                           {.create_graph = true});
  };
  const ad::CheckResult r = ad::gradgradcheck(hessian_blocks, {random_matrix(2, 3, 10)});
  EXPECT_TRUE(r.ok) << r.worst << "\n" << r.log;
}

TEST(RowHessian, OfAFunctionLinearInXIsZero) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(4, 3, 11));
  const VarD w = VarD::leaf(random_matrix(3, 1, 12));
  const VarD blocks = ad::row_hessian(ad::matmul(x, w), x, {.create_graph = true});
  EXPECT_EQ(blocks.rows(), 4);
  EXPECT_EQ(blocks.cols(), 9);
  EXPECT_TRUE(blocks.value().isZero());
}

TEST(RowJacobian, CoupledRowsAreSummedIntoTheBlocksNotDetected) {
  // y = x * sum_rows(x): row r' of y depends on every row of x, which breaks the promise.
  // row_jacobian then returns sum_r' dy[r'] / dx[r] (here 2 s_i on the diagonal, s = column
  // sums), not the per-row block dy[r] / dx[r] (s_i + x[r, i]). Documented, not detected.
  const MatrixD x0 = random_matrix(3, 2, 13);
  const auto f = [](const VarD& x) { return x * ad::sum_rows(x); };
  ad::TapeScope scope;
  const VarD x = VarD::leaf(x0);
  const MatrixD rows = ad::row_jacobian(f(x), x).value();
  const MatrixD full = ad::jacobian<double>(f, x0);  // (3*2) x (3*2)
  const Eigen::RowVectorXd s = x0.colwise().sum();
  for (Eigen::Index r = 0; r < 3; ++r) {
    MatrixD summed = MatrixD::Zero(2, 2);
    for (Eigen::Index rp = 0; rp < 3; ++rp) summed += full.block(rp * 2, r * 2, 2, 2);
    EXPECT_LT((rows.row(r) - summed.reshaped<Eigen::RowMajor>().transpose()).norm(), 1e-14);
    const MatrixD own_block = full.block(r * 2, r * 2, 2, 2);
    EXPECT_GT((rows.row(r) - own_block.reshaped<Eigen::RowMajor>().transpose()).norm(), 1e-3)
        << "row " << r << ": coupled rows happened to agree with the per-row block";
    EXPECT_NEAR(rows(r, 0), 2 * s(0), 1e-14);
  }
}

TEST(RowJacobian, ShapeMismatchesThrow) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(4, 3, 14));
  const VarD other = VarD::leaf(random_matrix(5, 3, 15));
  EXPECT_THROW(ad::row_jacobian(ad::tanh(other), x), ad::Error);
  EXPECT_THROW(ad::row_hessian(ad::tanh(x), x), ad::Error);  // 4x3, not one scalar per row
  EXPECT_THROW(ad::row_hessian(ad::sum_cols(ad::tanh(other)), x), ad::Error);
}

// ---- the Lagrangian network -------------------------------------------------------------------

// L(q, qdot) = |qdot|^2 / 2 + 0.1 MLP(q, qdot): the kinetic term keeps the mass matrix
// d^2 L / dqdot^2 near the identity, so it is well conditioned for any small MLP.
VarD Lagrangian(const std::vector<VarD>& params, const VarD& q, const VarD& qdot) {
  const VarD mlp = SmoothMlp(params, ad::concat_cols<double>({q, qdot}));
  return ad::scale(ad::sum_cols(ad::square(qdot)), 0.5) + ad::scale(mlp, 0.1);
}

// qddot = M^-1 (dL/dq - C qdot), M = d^2 L / dqdot^2, C[i][j] = d^2 L / dqdot_i dq_j.
VarD Acceleration(const std::vector<VarD>& params, const VarD& q, const VarD& qdot) {
  const VarD l = Lagrangian(params, q, qdot);
  const std::vector<VarD> g = ad::grad<double>({l}, {q, qdot}, {.create_graph = true});
  const VarD mass = ad::row_jacobian(g[1], qdot, {.create_graph = true});
  const VarD mixed = ad::row_jacobian(g[1], q, {.create_graph = true});
  return ad::batched_solve(mass, g[0] - ad::batched_matvec(mixed, qdot));
}

TEST(LagrangianAcceleration, MatchesAPerRowHessianAndSolve) {
  const Eigen::Index n = 2, rows = 4;
  const std::vector<MatrixD> params = ad::testing::mlp_parameters({2 * n, 8, 8, 1}, 16);
  const MatrixD q0 = random_matrix(rows, n, 17), qdot0 = random_matrix(rows, n, 18);
  ad::TapeScope scope;
  const std::vector<VarD> p = ad::testing::as_leaves<double>(params);
  const MatrixD qddot = Acceleration(p, VarD::leaf(q0), VarD::leaf(qdot0)).value();
  const auto on_row = [&](const VarD& x) {
    return Lagrangian(ad::testing::as_leaves<double>(params), ad::slice_cols(x, 0, n),
                      ad::slice_cols(x, n, n));
  };
  for (Eigen::Index r = 0; r < rows; ++r) {
    MatrixD x(1, 2 * n);
    x << q0.row(r), qdot0.row(r);
    const Eigen::MatrixXd h = ad::hessian<double>(on_row, x);
    const Eigen::VectorXd g = ad::jacobian<double>(on_row, x).row(0).transpose();
    const Eigen::MatrixXd mass = h.bottomRightCorner(n, n), mixed = h.bottomLeftCorner(n, n);
    const Eigen::VectorXd expected =
        mass.partialPivLu().solve(g.head(n) - mixed * qdot0.row(r).transpose());
    EXPECT_LT((qddot.row(r).transpose() - expected).norm(), 1e-13 * (1 + expected.norm()))
        << "row " << r;
  }
}

TEST(LagrangianAcceleration, TrainingGradientMatchesFiniteDifferences) {
  // The gradient of a loss on qddot with respect to q, qdot and the parameters: third
  // derivatives of L through row_jacobian and batched_solve.
  const std::vector<MatrixD> params = ad::testing::mlp_parameters({4, 5, 5, 1}, 19);
  std::vector<MatrixD> inputs = {random_matrix(2, 2, 20), random_matrix(2, 2, 21)};
  inputs.insert(inputs.end(), params.begin(), params.end());
  const auto acceleration = [](const Inputs& in) {
    return Acceleration(std::vector<VarD>(in.begin() + 2, in.end()), in[0], in[1]);
  };
  const ad::CheckResult r = ad::gradcheck(acceleration, inputs);
  EXPECT_TRUE(r.ok) << r.worst << "\n" << r.log;
}

}  // namespace
