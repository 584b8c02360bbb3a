// Every op of autodiff/ops.h against central finite differences, to first and second order,
// on random inputs kept inside each op's domain. One table row per op and shape case.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "autodiff/autodiff.h"
#include "test_util.h"

namespace ad = hnn::ad;
using ad::Matrix;
using ad::Var;
using ad::testing::MatrixD;
using ad::testing::random_away_from_zero;
using ad::testing::random_matrix;
using VarD = Var<double>;
using Inputs = std::vector<VarD>;

namespace {

struct OpCase {
  std::string name;
  std::function<VarD(const Inputs&)> f;
  std::vector<MatrixD> inputs;
};

void PrintTo(const OpCase& c, std::ostream* os) { *os << c.name; }

MatrixD Any(Eigen::Index r, Eigen::Index c, unsigned seed) { return random_matrix(r, c, seed); }
MatrixD Positive(Eigen::Index r, Eigen::Index c, unsigned seed) {
  return random_matrix(r, c, seed, 0.5, 2.0);
}
MatrixD Nonzero(Eigen::Index r, Eigen::Index c, unsigned seed) {
  return random_away_from_zero(r, c, seed);
}

// add/sub/mul/div over every broadcasting pattern: full, 1xC row, Rx1 column, 1x1 scalar, on
// either side, and row against column. The divisor stays positive.
void AddBinaryCases(std::vector<OpCase>& cases) {
  struct Shape {
    const char* name;
    Eigen::Index rows, cols;
  };
  const std::vector<std::pair<Shape, Shape>> shapes = {
      {{"full", 3, 4}, {"full", 3, 4}},   {{"full", 3, 4}, {"row", 1, 4}},
      {{"row", 1, 4}, {"full", 3, 4}},    {{"full", 3, 4}, {"col", 3, 1}},
      {{"col", 3, 1}, {"full", 3, 4}},    {{"full", 3, 4}, {"scalar", 1, 1}},
      {{"scalar", 1, 1}, {"full", 3, 4}}, {{"col", 3, 1}, {"row", 1, 4}},
  };
  const std::vector<std::pair<const char*, VarD (*)(const VarD&, const VarD&)>> ops = {
      {"Add", ad::add<double>},
      {"Sub", ad::sub<double>},
      {"Mul", ad::mul<double>},
      {"Div", ad::div<double>},
  };
  unsigned seed = 100;
  for (const auto& [op_name, op] : ops) {
    for (const auto& [a, b] : shapes) {
      const bool divide = std::string(op_name) == "Div";
      cases.push_back({std::string(op_name) + "_" + a.name + "_" + b.name,
                       [op = op](const Inputs& in) { return op(in[0], in[1]); },
                       {Any(a.rows, a.cols, seed), divide ? Positive(b.rows, b.cols, seed + 1)
                                                          : Any(b.rows, b.cols, seed + 1)}});
      seed += 2;
    }
  }
}

void AddUnaryCases(std::vector<OpCase>& cases) {
  const auto unary = [&](const std::string& name, MatrixD x, std::function<VarD(const VarD&)> op) {
    cases.push_back({name, [op](const Inputs& in) { return op(in[0]); }, {std::move(x)}});
  };
  unary("Neg", Any(3, 4, 1), [](const VarD& x) { return ad::neg(x); });
  unary("Scale", Any(3, 4, 2), [](const VarD& x) { return ad::scale(x, 2.5); });
  unary("Shift", Any(3, 4, 3), [](const VarD& x) { return ad::shift(x, -0.7); });
  unary("Square", Any(3, 4, 4), [](const VarD& x) { return ad::square(x); });
  unary("PowFractional", Positive(3, 4, 5), [](const VarD& x) { return ad::pow(x, 2.5); });
  unary("PowNegative", Positive(3, 4, 6), [](const VarD& x) { return ad::pow(x, -1.5); });
  unary("PowCube", Positive(3, 4, 7), [](const VarD& x) { return ad::pow(x, 3.0); });
  unary("Sqrt", Positive(3, 4, 8), [](const VarD& x) { return ad::sqrt(x); });
  unary("Exp", Any(3, 4, 9), [](const VarD& x) { return ad::exp(x); });
  unary("Log", Positive(3, 4, 10), [](const VarD& x) { return ad::log(x); });
  unary("Sin", random_matrix(3, 4, 11, -3, 3), [](const VarD& x) { return ad::sin(x); });
  unary("Cos", random_matrix(3, 4, 12, -3, 3), [](const VarD& x) { return ad::cos(x); });
  unary("Tanh", random_matrix(3, 4, 13, -2, 2), [](const VarD& x) { return ad::tanh(x); });
  unary("Sigmoid", random_matrix(3, 4, 14, -3, 3), [](const VarD& x) { return ad::sigmoid(x); });
  unary("Relu", Nonzero(3, 4, 15), [](const VarD& x) { return ad::relu(x); });
  unary("Softplus", random_matrix(3, 4, 16, -3, 3), [](const VarD& x) { return ad::softplus(x); });
  unary("Elu", Nonzero(3, 4, 17), [](const VarD& x) { return ad::elu(x); });
  unary("EluAlpha", Nonzero(3, 4, 18), [](const VarD& x) { return ad::elu(x, 0.3); });
  unary("Selu", Nonzero(3, 4, 19), [](const VarD& x) { return ad::selu(x); });
  unary("Swish", random_matrix(3, 4, 20, -3, 3), [](const VarD& x) { return ad::swish(x); });
  unary("Step", Nonzero(3, 4, 21), [](const VarD& x) { return ad::step(x) * x; });
  unary("Transpose", Any(3, 4, 22), [](const VarD& x) { return ad::transpose(x); });
  // The operators with a scalar on either side.
  unary("ScalarTimes", Any(3, 4, 23), [](const VarD& x) { return 2.0 * x; });
  unary("TimesScalar", Any(3, 4, 24), [](const VarD& x) { return x * -3.0; });
  unary("OverScalar", Any(3, 4, 25), [](const VarD& x) { return x / 4.0; });
  unary("ScalarPlus", Any(3, 4, 26), [](const VarD& x) { return 1.5 + x; });
  unary("PlusScalar", Any(3, 4, 27), [](const VarD& x) { return x + 1.5; });
  unary("ScalarMinus", Any(3, 4, 28), [](const VarD& x) { return 1.5 - x; });
  unary("MinusScalar", Any(3, 4, 29), [](const VarD& x) { return x - 1.5; });
  unary("UnaryMinus", Any(3, 4, 30), [](const VarD& x) { return -x; });
  // Reductions.
  unary("Sum", Any(3, 4, 31), [](const VarD& x) { return ad::sum(x); });
  unary("Mean", Any(3, 4, 32), [](const VarD& x) { return ad::mean(x); });
  unary("SumRows", Any(3, 4, 33), [](const VarD& x) { return ad::sum_rows(x); });
  unary("SumCols", Any(3, 4, 34), [](const VarD& x) { return ad::sum_cols(x); });
  unary("MeanRows", Any(3, 4, 35), [](const VarD& x) { return ad::mean_rows(x); });
  unary("MeanCols", Any(3, 4, 36), [](const VarD& x) { return ad::mean_cols(x); });
  // Broadcasting and its adjoint.
  unary("BroadcastRow", Any(1, 4, 37), [](const VarD& x) { return ad::broadcast_to(x, 3, 4); });
  unary("BroadcastCol", Any(3, 1, 38), [](const VarD& x) { return ad::broadcast_to(x, 3, 4); });
  unary("BroadcastScalar", Any(1, 1, 39), [](const VarD& x) { return ad::broadcast_to(x, 3, 4); });
  unary("BroadcastSame", Any(3, 4, 40), [](const VarD& x) { return ad::broadcast_to(x, 3, 4); });
  unary("SumToRow", Any(3, 4, 41), [](const VarD& x) { return ad::sum_to(x, 1, 4); });
  unary("SumToCol", Any(3, 4, 42), [](const VarD& x) { return ad::sum_to(x, 3, 1); });
  unary("SumToScalar", Any(3, 4, 43), [](const VarD& x) { return ad::sum_to(x, 1, 1); });
  unary("SumToSame", Any(3, 4, 44), [](const VarD& x) { return ad::sum_to(x, 3, 4); });
  // Columns.
  unary("SliceCols", Any(3, 4, 45), [](const VarD& x) { return ad::slice_cols(x, 1, 2); });
  unary("SliceAllCols", Any(3, 4, 46), [](const VarD& x) { return ad::slice_cols(x, 0, 4); });
  unary("PadCols", Any(3, 2, 47), [](const VarD& x) { return ad::pad_cols(x, 1, 5); });
  unary("Reshape", Any(1, 12, 149), [](const VarD& x) { return ad::reshape(x, 3, 4); });
  unary("ReshapeSquared", Any(3, 4, 150),
        [](const VarD& x) { return ad::square(ad::reshape(x, 2, 6)); });
  unary("ConcatSelf", Any(3, 2, 48), [](const VarD& x) {
    return ad::concat_cols<double>({x, ad::sin(x), x});
  });
  // A self product: both matmul operands are the same leaf, so gradients must add up.
  unary("MatmulGram", Any(3, 4, 49), [](const VarD& x) { return ad::matmul(x, x, true, false); });
}

void AddMultiInputCases(std::vector<OpCase>& cases) {
  for (const bool ta : {false, true}) {
    for (const bool tb : {false, true}) {
      // op(a) is 3x4 and op(b) is 4x2.
      const std::string name = std::string("Matmul") + (ta ? "T" : "N") + (tb ? "T" : "N");
      cases.push_back({name,
                       [ta, tb](const Inputs& in) { return ad::matmul(in[0], in[1], ta, tb); },
                       {ta ? Any(4, 3, 50) : Any(3, 4, 50), tb ? Any(2, 4, 51) : Any(4, 2, 51)}});
    }
  }
  cases.push_back({"LinearWithBias",
                   [](const Inputs& in) { return ad::linear(in[0], in[1], in[2]); },
                   {Any(3, 4, 52), Any(4, 2, 53), Any(1, 2, 54)}});
  cases.push_back({"LinearWithoutBias",
                   [](const Inputs& in) { return ad::linear(in[0], in[1]); },
                   {Any(3, 4, 55), Any(4, 2, 56)}});
  cases.push_back({"TanhBackward",
                   [](const Inputs& in) { return ad::tanh_backward(in[0], in[1]); },
                   {Any(3, 4, 57), random_matrix(3, 4, 58, -0.9, 0.9)}});
  cases.push_back({"TanhBackwardOfTanh",
                   [](const Inputs& in) { return ad::tanh_backward(in[0], ad::tanh(in[1])); },
                   {Any(3, 4, 59), Any(3, 4, 60)}});
  cases.push_back({"ConcatCols",
                   [](const Inputs& in) {
                     return ad::concat_cols<double>({in[0], in[1], in[2]});
                   },
                   {Any(3, 1, 61), Any(3, 3, 62), Any(3, 2, 63)}});
}

std::vector<OpCase> AllCases() {
  std::vector<OpCase> cases;
  AddBinaryCases(cases);
  AddUnaryCases(cases);
  AddMultiInputCases(cases);
  return cases;
}

class OpDerivatives : public ::testing::TestWithParam<OpCase> {};

TEST_P(OpDerivatives, GradcheckMatchesFiniteDifferences) {
  const ad::CheckResult r = ad::gradcheck(GetParam().f, GetParam().inputs);
  EXPECT_TRUE(r.ok) << "worst: " << r.worst << "\n" << r.log;
}

TEST_P(OpDerivatives, GradgradcheckMatchesFiniteDifferences) {
  const ad::CheckResult r = ad::gradgradcheck(GetParam().f, GetParam().inputs);
  EXPECT_TRUE(r.ok) << "worst: " << r.worst << "\n" << r.log;
}

// sin(op(x)): its second derivative runs through the op's recorded backward with an incoming
// gradient that depends on x, which the op alone does not exercise when it is linear.
TEST_P(OpDerivatives, GradgradcheckOfSinOfOpMatchesFiniteDifferences) {
  const auto f = GetParam().f;
  const ad::CheckResult r =
      ad::gradgradcheck([f](const Inputs& in) { return ad::sin(f(in)); }, GetParam().inputs);
  EXPECT_TRUE(r.ok) << "worst: " << r.worst << "\n" << r.log;
}

INSTANTIATE_TEST_SUITE_P(AllOps, OpDerivatives, ::testing::ValuesIn(AllCases()),
                         [](const ::testing::TestParamInfo<OpCase>& info) {
                           return info.param.name;
                         });

// Forward values against the scalar standard library, in both scalar types: derivative checks
// only compare an op with itself, so the values need their own reference. The tolerance is a
// few ulps of max(1, |y|) (Eigen's vectorised functions are not correctly rounded).
template <typename T>
class OpValues : public ::testing::Test {};
using ScalarTypes = ::testing::Types<float, double>;
TYPED_TEST_SUITE(OpValues, ScalarTypes);

TYPED_TEST(OpValues, MatchTheStandardLibrary) {
  using T = TypeParam;
  using Op = Var<T> (*)(const Var<T>&);
  struct Case {
    const char* name;
    Op op;
    double (*reference)(double);
    double lo, hi;
  };
  const std::vector<Case> cases = {
      {"exp", ad::exp<T>, [](double x) { return std::exp(x); }, -10, 10},
      {"log", ad::log<T>, [](double x) { return std::log(x); }, 1e-3, 1e3},
      {"sqrt", ad::sqrt<T>, [](double x) { return std::sqrt(x); }, 0, 100},
      {"sin", ad::sin<T>, [](double x) { return std::sin(x); }, -10, 10},
      {"cos", ad::cos<T>, [](double x) { return std::cos(x); }, -10, 10},
      {"tanh", ad::tanh<T>, [](double x) { return std::tanh(x); }, -20, 20},
      {"sigmoid", ad::sigmoid<T>, [](double x) { return 1 / (1 + std::exp(-x)); }, -30, 30},
      {"softplus", ad::softplus<T>, [](double x) { return std::log1p(std::exp(x)); }, -30, 30},
      {"relu", ad::relu<T>, [](double x) { return std::max(x, 0.0); }, -5, 5},
      {"square", ad::square<T>, [](double x) { return x * x; }, -5, 5},
      {"swish", ad::swish<T>, [](double x) { return x / (1 + std::exp(-x)); }, -30, 30},
  };
  const double ulp = std::numeric_limits<T>::epsilon();
  for (const Case& c : cases) {
    ad::TapeScope scope;
    const MatrixD x = random_matrix(1, 2000, 80, c.lo, c.hi);
    const Matrix<T> xt = x.cast<T>();
    const Matrix<T> y = c.op(Var<T>::constant(xt)).value();
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      const double expected = c.reference(double(xt(0, i)));
      ASSERT_NEAR(double(y(0, i)), expected, 8 * ulp * std::max(1.0, std::abs(expected)))
          << c.name << "(" << xt(0, i) << ")";
    }
  }
}

// Identities in the style of Ceres' jet tests: they check values and derivatives together.
TEST(OpIdentities, LogOfExpIsIdentityWithUnitDerivative) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(2, 3, 70, -2, 2));
  const VarD y = ad::log(ad::exp(x));
  EXPECT_TRUE(y.value().isApprox(x.value(), 1e-14));
  const VarD g = ad::grad<double>({ad::sum(y)}, {x})[0];
  EXPECT_TRUE(g.value().isApprox(MatrixD::Ones(2, 3), 1e-14));
}

TEST(OpIdentities, SinSquaredPlusCosSquaredIsOneWithZeroDerivative) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(2, 3, 71, -3, 3));
  const VarD y = ad::square(ad::sin(x)) + ad::square(ad::cos(x));
  EXPECT_TRUE(y.value().isApprox(MatrixD::Ones(2, 3), 1e-14));
  const VarD g = ad::grad<double>({ad::sum(y)}, {x})[0];
  EXPECT_LT(g.value().cwiseAbs().maxCoeff(), 1e-14);
}

TEST(OpIdentities, SeluMatchesItsDefinition) {
  ad::TapeScope scope;
  const MatrixD x0 = random_away_from_zero(2, 3, 72);
  const VarD y = ad::selu(VarD::constant(x0));
  for (Eigen::Index i = 0; i < x0.size(); ++i) {
    const double x = x0.data()[i];
    const double expected =
        1.0507009873554805 * (x > 0 ? x : 1.6732632423543772 * (std::exp(x) - 1));
    EXPECT_NEAR(y.value().data()[i], expected, 1e-14);
  }
}

TEST(OpIdentities, SoftplusIsStableForLargeInputs) {
  ad::TapeScope scope;
  MatrixD x0(1, 4);
  x0 << -800, -30, 30, 800;
  const VarD x = VarD::leaf(x0);
  const VarD y = ad::softplus(x);
  EXPECT_NEAR(y.value()(0, 0), 0, 1e-300);
  EXPECT_NEAR(y.value()(0, 1), std::exp(-30.0), 1e-20);
  EXPECT_NEAR(y.value()(0, 2), 30, 1e-12);
  EXPECT_EQ(y.value()(0, 3), 800);
  const VarD g = ad::grad<double>({ad::sum(y)}, {x})[0];
  EXPECT_TRUE(g.value().allFinite());
  EXPECT_NEAR(g.value()(0, 3), 1, 1e-15);
}

// Big elementwise ops split their rows across the engine's threads: the values, and the
// gradients through them, are the same bit for bit on 1 and 2 threads.
TEST(ElementwiseThreads, BigOpsGiveTheSameValuesOnOneAndTwoThreads) {
  const MatrixD a0 = ad::testing::random_matrix(600, 200, 31),
                b0 = ad::testing::random_matrix(1, 200, 32);
  const auto run = [&](int threads) {
    ad::set_num_threads(threads);
    ad::TapeScope scope;
    const VarD a = VarD::leaf(a0), b = VarD::leaf(b0);
    const VarD y = ad::softplus(a) * b + ad::sigmoid(a) - a / (b * b + 1.0);
    const std::vector<VarD> g = ad::grad<double>({ad::sum(ad::square(y))}, {a, b});
    ad::set_num_threads(2);
    return std::vector<MatrixD>{y.value(), g[0].value(), g[1].value()};
  };
  const std::vector<MatrixD> one = run(1), two = run(2);
  for (std::size_t i = 0; i < one.size(); ++i) EXPECT_EQ(one[i], two[i]) << "result " << i;
}

}  // namespace

// Slices, pads and joins copy their columns with plain loops (autodiff/row_kernels.h): exactly
// the columns, at one column of many rows too.
TEST(ShapeOps, NarrowSlicesPadsAndJoinsCopyTheirColumnsExactly) {
  const MatrixD x = random_matrix(130, 3, 7);
  const VarD v = VarD::constant(x);
  EXPECT_EQ(ad::slice_cols(v, 1, 1).value(), x.middleCols(1, 1));
  EXPECT_EQ(ad::slice_cols(v, 1, 2).value(), x.middleCols(1, 2));
  MatrixD padded = MatrixD::Zero(130, 6);
  padded.middleCols(2, 3) = x;
  EXPECT_EQ(ad::pad_cols(v, 2, 6).value(), padded);
  const MatrixD joined = ad::concat_cols<double>({ad::slice_cols(v, 2, 1), v}).value();
  EXPECT_EQ(joined.col(0), x.col(2));
  EXPECT_EQ(joined.rightCols(3), x);
}

TEST(ShapeOps, ReshapeKeepsColumnMajorOrder) {
  const MatrixD x = random_matrix(1, 6, 8);
  const MatrixD y = ad::reshape(VarD::constant(x), 2, 3).value();
  for (int k = 0; k < 6; ++k) EXPECT_EQ(y(k % 2, k / 2), x(0, k));
}

// A broadcast error names the op and both shapes (formatted only when it is thrown).
TEST(ShapeOps, ShapesThatDoNotBroadcastAreNamedInTheError) {
  const VarD a = VarD::constant(random_matrix(2, 3, 1)), b = VarD::constant(random_matrix(3, 2, 2));
  try {
    (void)ad::add(a, b);
    FAIL() << "add of 2x3 and 3x2 did not throw";
  } catch (const ad::Error& e) {
    EXPECT_EQ(std::string(e.what()), "add: shapes 2x3 and 3x2 cannot be broadcast together");
  }
}
