// The engine's mechanics: grad() and backward() semantics, grad mode, tape scopes, and the
// errors of misuse (each naming the op and the shapes involved).

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

#include "autodiff/autodiff.h"
#include "test_util.h"

namespace ad = hnn::ad;
using ad::Matrix;
using ad::Var;
using ad::testing::MatrixD;
using ad::testing::random_matrix;
using VarD = Var<double>;

namespace {

// The message of the hnn::ad::Error thrown by `f` ("" when it throws nothing).
std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ad::Error& e) {
    return e.what();
  }
  return "";
}

// Whether `text` contains `part`, with the whole text in the failure message.
::testing::AssertionResult Contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "\"" << part << "\" not found in \"" << text << "\"";
}

TEST(Grad, OfAProductIsTheOtherFactor) {
  ad::TapeScope scope;
  const VarD a = VarD::leaf(MatrixD::Constant(2, 3, 2.0));
  const VarD b = VarD::leaf(MatrixD::Constant(2, 3, 5.0));
  const auto g = ad::grad<double>({ad::sum(a * b)}, {a, b});
  EXPECT_TRUE(g[0].value().isApprox(b.value()));
  EXPECT_TRUE(g[1].value().isApprox(a.value()));
}

TEST(Grad, HnnLossThroughAGradientMatchesFiniteDifferences) {
  // A small tanh MLP H(x); loss = mean((J grad_x H - target)^2), checked in the weights to
  // first and second order.
  const MatrixD x0 = random_matrix(5, 2, 1), target = random_matrix(5, 2, 2);
  const auto loss = [&](const std::vector<VarD>& w) {
    return ad::testing::hnn_loss<double>(w, VarD::leaf(x0), VarD::constant(target));
  };
  const std::vector<MatrixD> w = ad::testing::mlp_parameters({2, 4, 1}, 3);
  const ad::CheckResult first = ad::gradcheck(loss, w);
  EXPECT_TRUE(first.ok) << first.worst << "\n" << first.log;
  const ad::CheckResult second = ad::gradgradcheck(loss, w);
  EXPECT_TRUE(second.ok) << second.worst << "\n" << second.log;
}

TEST(Grad, WithoutCreateGraphReturnsConstants) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(2, 2, 4));
  const VarD g = ad::grad<double>({ad::sum(ad::sin(x))}, {x})[0];
  EXPECT_FALSE(g.requires_grad());
  const VarD gg = ad::grad<double>({ad::sum(ad::sin(x))}, {x}, {.create_graph = true})[0];
  EXPECT_TRUE(gg.requires_grad());
  EXPECT_TRUE(gg.value().isApprox(g.value()));
}

TEST(Grad, DoesNotTouchTheLeavesAccumulatedGradient) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(2, 2, 5));
  ad::grad<double>({ad::sum(ad::square(x))}, {x});
  EXPECT_FALSE(x.has_grad());
}

TEST(Grad, WithRespectToAnIntermediateResult) {
  // z = exp(x) is a target; x requires gradients but is not asked for.
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(2, 3, 6));
  const VarD z = ad::exp(x);
  const VarD y = ad::sum(ad::square(z));
  const auto g = ad::grad<double>({y}, {z});
  EXPECT_TRUE(g[0].value().isApprox(2 * z.value()));
  // An output is its own gradient's target too: dy/dy = 1.
  EXPECT_DOUBLE_EQ(ad::grad<double>({y}, {y})[0].item(), 1.0);
  // Intermediate and leaf together.
  const auto both = ad::grad<double>({y}, {z, x});
  EXPECT_TRUE(both[0].value().isApprox(2 * z.value()));
  EXPECT_TRUE(both[1].value().isApprox(2 * z.value().cwiseProduct(z.value())));
}

TEST(Grad, SumsOverOutputsWeightedByGradOutputs) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(2, 3, 7));
  const MatrixD v1 = random_matrix(2, 3, 8), v2 = random_matrix(2, 3, 9);
  const auto g = ad::grad<double>({ad::sin(x), ad::square(x)}, {x}, {},
                                  {VarD::constant(v1), VarD::constant(v2)});
  const MatrixD expected =
      v1.cwiseProduct(MatrixD(x.value().array().cos())) + 2 * v2.cwiseProduct(x.value());
  EXPECT_TRUE(g[0].value().isApprox(expected));
  // The same output twice counts twice.
  const VarD s = ad::sum(x);
  EXPECT_TRUE(ad::grad<double>({s, s}, {x})[0].value().isApprox(MatrixD::Constant(2, 3, 2.0)));
}

TEST(Grad, IntoAReusedVectorWithAGradOutputMatchesGrad) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(2, 3, 7));
  const VarD seed = VarD::constant(random_matrix(2, 3, 8));
  std::vector<VarD> result;
  ad::grad_into(ad::sin(x), {x}, result, {}, seed);
  ASSERT_EQ(result.size(), 1u);
  EXPECT_TRUE(
      result[0].value().isApprox(ad::grad<double>({ad::sin(x)}, {x}, {}, {seed})[0].value()));
}

TEST(Variable, IsDifferentiableLikeALeafAndLivesOnTheTape) {
  const MatrixD x0 = random_matrix(3, 2, 5);
  const std::size_t before = ad::Tape<double>::current().size();
  {
    ad::TapeScope scope;
    const VarD x = VarD::variable(x0);
    EXPECT_TRUE(x.requires_grad());
    EXPECT_FALSE(x.is_leaf());
    const VarD dx = ad::grad<double>({ad::sum(ad::square(x))}, {x}, {.create_graph = true})[0];
    EXPECT_TRUE(dx.value().isApprox(2 * x0));
    // The derivative stays differentiable in x: d/dx sum((2x)^2) = 8x.
    EXPECT_TRUE(ad::grad<double>({ad::sum(ad::square(dx))}, {x})[0].value().isApprox(8 * x0));
  }
  EXPECT_EQ(ad::Tape<double>::current().size(), before);  // recycled with the scope
}

TEST(ConcatCols, OfABracedListMatchesTheVectorForm) {
  ad::TapeScope scope;
  const VarD a = VarD::leaf(random_matrix(2, 1, 1)), b = VarD::leaf(random_matrix(2, 2, 2));
  const VarD listed = ad::concat_cols<double>({a, b});
  EXPECT_EQ(listed.value(), ad::concat_cols(std::vector<VarD>{a, b}).value());
  const auto g = ad::grad<double>({ad::sum(listed * listed)}, {a, b});
  EXPECT_TRUE(g[0].value().isApprox(2 * a.value()));
  EXPECT_TRUE(g[1].value().isApprox(2 * b.value()));
}

TEST(Grad, SurvivesAVeryLongChain) {
  // 100000 nodes: the sweep and the tape are iterative, so nothing recurses this deep.
  ad::TapeScope scope;
  const VarD x = VarD::leaf(MatrixD::Constant(1, 1, 1.0));
  VarD y = x;
  constexpr int kLength = 100000;
  for (int i = 0; i < kLength; ++i) y = y * 1.00001;
  EXPECT_NEAR(ad::grad<double>({y}, {x})[0].item(), std::pow(1.00001, kLength), 1e-9);
}

TEST(Grad, SharedSubexpressionsAreVisitedOnce) {
  // y = (((x + x) + (x + x)) ...) doubles 40 times: a naive tree walk would take 2^40 steps.
  ad::TapeScope scope;
  const VarD x = VarD::leaf(MatrixD::Constant(1, 1, 1.0));
  VarD y = x;
  for (int i = 0; i < 40; ++i) y = y + y;
  EXPECT_DOUBLE_EQ(ad::grad<double>({y}, {x})[0].item(), std::ldexp(1.0, 40));
}

TEST(AllowUnused, UnusedInputThrowsWithoutIt) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(2, 3, 10)), unused = VarD::leaf(random_matrix(4, 1, 11));
  const std::string message = ErrorOf([&] { ad::grad<double>({ad::sum(x)}, {x, unused}); });
  EXPECT_TRUE(Contains(message, "input #1"));
  EXPECT_TRUE(Contains(message, "4x1"));
  EXPECT_TRUE(Contains(message, "allow_unused"));
}

TEST(AllowUnused, UnusedInputGetsZerosOfItsShape) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(2, 3, 12)), unused = VarD::leaf(random_matrix(4, 1, 13));
  const auto g = ad::grad<double>({ad::sum(x)}, {x, unused}, {.allow_unused = true});
  EXPECT_TRUE(g[0].value().isApprox(MatrixD::Ones(2, 3)));
  EXPECT_EQ(g[1].rows(), 4);
  EXPECT_EQ(g[1].cols(), 1);
  EXPECT_TRUE(g[1].value().isZero());
}

TEST(AllowUnused, UsedOnlyThroughAConstantMaskCountsAsUnused) {
  // step(x) is a constant mask, so y depends on x through no differentiable path.
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(2, 3, 14)), w = VarD::leaf(random_matrix(2, 3, 15));
  const VarD y = ad::sum(ad::step(x) * w);
  EXPECT_TRUE(Contains(ErrorOf([&] { ad::grad<double>({y}, {x}); }), "not used"));
  EXPECT_TRUE(ad::grad<double>({y}, {x}, {.allow_unused = true})[0].value().isZero());
}

TEST(Backward, AccumulatesIntoLeaves) {
  ad::TapeScope scope;
  VarD a = VarD::leaf(random_matrix(2, 3, 16)), b = VarD::leaf(random_matrix(2, 3, 17));
  const VarD y = ad::sum(a * b);
  EXPECT_TRUE(a.grad().isZero());  // zeros before any backward
  ad::backward(y);
  EXPECT_TRUE(a.grad().isApprox(b.value()));
  EXPECT_TRUE(b.grad().isApprox(a.value()));
  ad::backward(y);
  EXPECT_TRUE(a.grad().isApprox(2 * b.value()));
  EXPECT_TRUE(b.grad().isApprox(2 * a.value()));
  a.zero_grad();
  EXPECT_TRUE(a.grad().isZero());
  EXPECT_TRUE(b.grad().isApprox(2 * a.value()));  // untouched by a.zero_grad()
}

TEST(Backward, SkipsLeavesThatDoNotRequireGradients) {
  ad::TapeScope scope;
  const VarD a = VarD::leaf(random_matrix(2, 3, 18));
  const VarD frozen = VarD::leaf(random_matrix(2, 3, 19), /*requires_grad=*/false);
  ad::backward(ad::sum(a * frozen));
  EXPECT_TRUE(a.grad().isApprox(frozen.value()));
  EXPECT_FALSE(frozen.has_grad());
}

TEST(Backward, TakesAGradOutputForNonScalarOutputs) {
  ad::TapeScope scope;
  const VarD a = VarD::leaf(random_matrix(2, 3, 20));
  const MatrixD v = random_matrix(2, 3, 21);
  EXPECT_TRUE(Contains(ErrorOf([&] { ad::backward(ad::square(a)); }), "2x3"));
  ad::backward(ad::square(a), VarD::constant(v));
  EXPECT_TRUE(a.grad().isApprox(2 * v.cwiseProduct(a.value())));
}

TEST(GradMode, NoGradGuardRecordsValuesOnlyAndRestores) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(2, 3, 22));
  EXPECT_TRUE(ad::grad_enabled());
  VarD y;
  {
    ad::NoGradGuard no_grad;
    EXPECT_FALSE(ad::grad_enabled());
    {
      ad::NoGradGuard nested;
      EXPECT_FALSE(ad::grad_enabled());
    }
    EXPECT_FALSE(ad::grad_enabled());
    y = ad::sum(ad::exp(x));
  }
  EXPECT_TRUE(ad::grad_enabled());
  EXPECT_DOUBLE_EQ(y.item(), x.value().array().exp().sum());
  EXPECT_FALSE(y.requires_grad());
  const std::string message = ErrorOf([&] { ad::grad<double>({y}, {x}); });
  EXPECT_TRUE(Contains(message, "does not require gradients"));
  EXPECT_TRUE(Contains(message, "NoGradGuard"));
  EXPECT_TRUE(Contains(ErrorOf([&] { ad::backward(y); }), "NoGradGuard"));
}

TEST(TapeScopes, RewindTheTapeAndNest) {
  auto& tape = ad::Tape<double>::current();
  const std::size_t start = tape.size();
  {
    ad::TapeScope outer;
    const VarD a = VarD::constant(MatrixD::Ones(2, 2));
    const std::size_t after_a = tape.size();
    EXPECT_EQ(after_a, start + 1);
    {
      ad::TapeScope inner;
      VarD b = a + a;
      b = b * a;
      EXPECT_EQ(tape.size(), after_a + 2);
    }
    EXPECT_EQ(tape.size(), after_a);
    EXPECT_TRUE(a.value().isApprox(MatrixD::Ones(2, 2)));  // the outer scope's Var is alive
  }
  EXPECT_EQ(tape.size(), start);
}

TEST(TapeScopes, LeavesOutliveTheScopeThatUsedThem) {
  const VarD w = VarD::leaf(random_matrix(2, 2, 23));
  for (int step = 0; step < 3; ++step) {
    ad::TapeScope scope;
    const VarD g = ad::grad<double>({ad::sum(ad::square(w))}, {w})[0];
    EXPECT_TRUE(g.value().isApprox(2 * w.value()));
  }
  EXPECT_EQ(w.rows(), 2);
}

TEST(Errors, UsingAVarAfterItsTapeScopeEndedThrows) {
  const VarD x = VarD::leaf(random_matrix(2, 3, 24));
  VarD stale;
  {
    ad::TapeScope scope;
    stale = ad::tanh(x);
  }
  EXPECT_TRUE(Contains(ErrorOf([&] { (void)stale.value(); }), "op 'tanh'"));
  {
    ad::TapeScope reuse;  // the slot is recycled by a new result of another op
    const VarD other = ad::exp(x);
    const std::string message = ErrorOf([&] { (void)stale.value(); });
    EXPECT_TRUE(Contains(message, "after its TapeScope ended"));
    EXPECT_TRUE(Contains(ErrorOf([&] { (void)ad::sum(stale); }), "TapeScope"));
    EXPECT_TRUE(Contains(ErrorOf([&] { ad::grad<double>({ad::sum(x)}, {stale}); }), "TapeScope"));
    EXPECT_TRUE(other.value().isApprox(x.value().array().exp().matrix()));
  }
  EXPECT_TRUE(Contains(ErrorOf([&] { (void)VarD().value(); }), "empty Var"));
}

TEST(Errors, GradOfAConstantNamesTheInput) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(2, 3, 25));
  const VarD c = VarD::constant(random_matrix(3, 1, 26));
  const VarD frozen = VarD::leaf(random_matrix(1, 3, 27), /*requires_grad=*/false);
  const VarD y = ad::sum(ad::matmul(x, c) + ad::sum(frozen));
  std::string message = ErrorOf([&] { ad::grad<double>({y}, {x, c}); });
  EXPECT_TRUE(Contains(message, "input #1 (3x1 constant) does not require gradients"));
  EXPECT_TRUE(Contains(message, "Var::leaf"));
  message = ErrorOf([&] { ad::grad<double>({y}, {frozen}); });
  EXPECT_TRUE(Contains(message, "input #0 (1x3 leaf) does not require gradients"));
}

TEST(Errors, OutputOfConstantsOnly) {
  ad::TapeScope scope;
  const VarD c = VarD::constant(random_matrix(2, 2, 28));
  const VarD x = VarD::leaf(random_matrix(2, 2, 29));
  const VarD y = ad::sum(ad::exp(c));
  EXPECT_TRUE(Contains(ErrorOf([&] { ad::grad<double>({y}, {x}); }),
                       "output #0 (1x1 sum) does not require gradients"));
}

TEST(Errors, MisuseOfLeafOnlyOperations) {
  ad::TapeScope scope;
  const VarD x = VarD::leaf(random_matrix(2, 3, 30));
  VarD y = ad::exp(x);
  EXPECT_TRUE(Contains(ErrorOf([&] { (void)y.grad(); }), "only leaves"));
  EXPECT_TRUE(Contains(ErrorOf([&] { y.mutable_value(); }), "op 'exp'"));
  EXPECT_TRUE(Contains(ErrorOf([&] { y.set_requires_grad(false); }), "op 'exp'"));
  EXPECT_TRUE(Contains(ErrorOf([&] { (void)y.item(); }), "2x3"));
  EXPECT_TRUE(Contains(ErrorOf([&] { ad::grad<double>({}, {x}); }), "no outputs"));
  EXPECT_TRUE(Contains(ErrorOf([&] {
                         ad::grad<double>({ad::sum(y)}, {x}, {},
                                          {VarD::constant(MatrixD::Ones(2, 2))});
                       }),
                       "grad_outputs[0] is 2x2 but output 0 is 1x1"));
  EXPECT_TRUE(Contains(
      ErrorOf([&] { ad::hessian<double>([](const VarD& v) { return v; }, MatrixD::Ones(2, 1)); }),
      "2x1"));
}

// Each shape error names the op and both shapes.
struct ShapeErrorCase {
  std::string name;
  std::function<void()> build;
  std::vector<std::string> expected;  // substrings of the message
};

void PrintTo(const ShapeErrorCase& c, std::ostream* os) { *os << c.name; }

VarD Leaf(Eigen::Index rows, Eigen::Index cols) { return VarD::leaf(MatrixD::Ones(rows, cols)); }

std::vector<ShapeErrorCase> ShapeErrorCases() {
  return {
      {"Add", [] { ad::add(Leaf(2, 3), Leaf(3, 2)); }, {"add", "2x3", "3x2"}},
      {"Sub", [] { ad::sub(Leaf(2, 3), Leaf(2, 4)); }, {"sub", "2x3", "2x4"}},
      {"Mul", [] { ad::mul(Leaf(2, 3), Leaf(3, 3)); }, {"mul", "2x3", "3x3"}},
      {"Div", [] { ad::div(Leaf(1, 2), Leaf(2, 3)); }, {"div", "1x2", "2x3"}},
      {"Operator", [] { (void)(Leaf(4, 1) * Leaf(3, 1)); }, {"mul", "4x1", "3x1"}},
      {"Matmul", [] { ad::matmul(Leaf(2, 3), Leaf(4, 5)); }, {"matmul", "2x3", "4x5"}},
      {"MatmulTransposed",
       [] { ad::matmul(Leaf(2, 3), Leaf(3, 2), false, true); },
       {"matmul", "2x3", "3x2^T"}},
      {"LinearWeight", [] { ad::linear(Leaf(2, 3), Leaf(4, 5)); }, {"linear", "2x3", "4x5"}},
      {"LinearBias",
       [] { ad::linear(Leaf(2, 3), Leaf(3, 5), Leaf(1, 4)); },
       {"linear", "1x4", "3x5"}},
      {"TanhBackward",
       [] { ad::tanh_backward(Leaf(2, 3), Leaf(3, 2)); },
       {"tanh_backward", "2x3", "3x2"}},
      {"ConcatCols",
       [] {
         ad::concat_cols<double>({Leaf(2, 3), Leaf(3, 3)});
       },
       {"concat_cols", "2x3", "3x3"}},
      {"BroadcastTo", [] { ad::broadcast_to(Leaf(2, 3), 4, 3); }, {"broadcast_to", "2x3", "4x3"}},
      {"SumTo", [] { ad::sum_to(Leaf(2, 3), 2, 2); }, {"sum_to", "2x3", "2x2"}},
      {"SliceCols", [] { ad::slice_cols(Leaf(2, 3), 2, 2); }, {"slice_cols", "2x3", "[2, 4)"}},
      {"PadCols", [] { ad::pad_cols(Leaf(2, 3), 1, 3); }, {"pad_cols", "2x3"}},
      {"Reshape", [] { ad::reshape(Leaf(2, 3), 4, 2); }, {"reshape", "2x3", "4x2"}},
  };
}

class ShapeErrors : public ::testing::TestWithParam<ShapeErrorCase> {};

TEST_P(ShapeErrors, ThrowWithTheOpAndBothShapes) {
  ad::TapeScope scope;
  const std::string message = ErrorOf(GetParam().build);
  ASSERT_FALSE(message.empty()) << "no hnn::ad::Error thrown";
  for (const std::string& part : GetParam().expected) EXPECT_TRUE(Contains(message, part));
}

INSTANTIATE_TEST_SUITE_P(AllOps, ShapeErrors, ::testing::ValuesIn(ShapeErrorCases()),
                         [](const ::testing::TestParamInfo<ShapeErrorCase>& info) {
                           return info.param.name;
                         });

TEST(Gradcheck, ReportsAWrongDerivativeAndWhereItIs) {
  // x * detached(x): the analytic derivative is x, the true one 2x.
  const auto f = [](const std::vector<VarD>& in) { return in[0] * VarD::constant(in[0].value()); };
  MatrixD x(1, 3);
  x << 0.5, -1.0, 2.0;
  const ad::CheckResult r = ad::gradcheck(f, {x});
  EXPECT_FALSE(r.ok);
  EXPECT_NEAR(r.max_error, 2.0, 1e-6);  // |2 - 4| at the third element
  EXPECT_TRUE(Contains(r.worst, "d output[2] / d input[2]"));
  EXPECT_TRUE(Contains(r.log, "d output[0] / d input[0]"));
}

TEST(Gradcheck, PassesOnACorrectDerivativeWithTinyError) {
  const ad::CheckResult r =
      ad::gradcheck([](const std::vector<VarD>& in) { return ad::sum(ad::exp(in[0]) * in[1]); },
                    {random_matrix(2, 2, 31), random_matrix(2, 2, 32)});
  EXPECT_TRUE(r.ok) << r.log;
  EXPECT_LT(r.max_error, 1e-8);
}

}  // namespace
