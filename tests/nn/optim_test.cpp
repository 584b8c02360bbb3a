// Adam (with parameter groups) and SGD against hand-computed steps, their argument checks, and
// no allocation per step.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "malloc_counter.h"
#include "nn_test_util.h"

namespace ad = hnn::ad;
namespace nn = hnn::nn;
using ad::Var;
using MatrixD = nn::Matrix<double>;

// ---- counting heap allocations --------------------------------------------------------------
// malloc is interposed by tests/malloc_counter.cpp (not under the sanitizers).

namespace {

// The number of heap allocations made by f().
template <typename F>
long allocations_in(F f) {
  const long before = hnn::testing::allocation_count();
  f();
  return hnn::testing::allocation_count() - before;
}

Var<double> row(std::initializer_list<double> values) {
  MatrixD m(1, Eigen::Index(values.size()));
  Eigen::Index i = 0;
  for (double v : values) m(0, i++) = v;
  return Var<double>::leaf(m, /*requires_grad=*/false);
}

void expect_row(const MatrixD& actual, const std::vector<double>& expected, double tol,
                const std::string& where) {
  ASSERT_EQ(actual.size(), Eigen::Index(expected.size())) << where;
  Eigen::Index i = 0;
  for (double e : expected) {
    EXPECT_NEAR(actual(0, i), e, tol) << where << ", element " << i;
    ++i;
  }
}

}  // namespace

TEST(Adam, FirstStepMovesEachParameterByLrTimesTheSignOfItsGradient) {
  // t = 1: m_hat = g and v_hat = g^2, so p -= lr g / (|g| + eps).
  Var<double> p = Var<double>::leaf(MatrixD{{1.0, -2.0, 0.5}});
  nn::Adam<double> adam({p}, {.lr = 0.1});
  adam.step({row({0.5, -1.0, 0.0})});
  expect_row(p.value(), {1.0 - 0.1 * 0.5 / (0.5 + 1e-8), -2.0 + 0.1 * 1.0 / (1.0 + 1e-8), 0.5},
             1e-16, "step 1");
  EXPECT_EQ(adam.step_count(), 1);
  expect_row(adam.first_moment(0), {0.05, -0.1, 0.0}, 1e-16, "m");
  expect_row(adam.second_moment(0), {0.00025, 0.001, 0.0}, 1e-18, "v");
}

// A float gradient of 1e20 squares past float's range, so v is inf; torch's step there is
// m / sqrt(inf) = 0. The entries run in whole SIMD packets, where an approximate sqrt (Eigen's
// fast one: a reciprocal estimate and a Newton step) gives NaN for inf.
TEST(Adam, AGradientWhoseSquareOverflowsLeavesItsParameterWhereItWas) {
  Var<float> p = Var<float>::leaf(nn::Matrix<float>::Ones(1, 64));
  nn::Adam<float> adam({p}, {.lr = 0.1});
  nn::Matrix<float> g = nn::Matrix<float>::Ones(1, 64);
  for (Eigen::Index i = 0; i < 64; i += 3) g(0, i) = 1e20f;
  adam.step({Var<float>::constant(g)});
  for (Eigen::Index i = 0; i < 64; ++i) {
    EXPECT_TRUE(std::isinf(adam.second_moment(0)(0, i)) == (i % 3 == 0)) << "v, element " << i;
    EXPECT_NEAR(p.value()(0, i), i % 3 == 0 ? 1.0f : 0.9f, 1e-5) << "element " << i;
  }
}

TEST(Adam, ThreeStepsMatchHandComputedValues) {
  // Expected values from PyTorch's formulas, evaluated step by step in double:
  //   g += wd p; m = 0.9 m + 0.1 g; v = 0.999 v + 0.001 g^2;
  //   p -= lr (m / (1 - 0.9^t)) / (sqrt(v / (1 - 0.999^t)) + 1e-8), lr = 0.1.
  const std::vector<std::vector<double>> grads{
      {0.5, -1.0, 0.0}, {0.1, 0.2, 1e-3}, {-0.3, 0.4, 2.0}};
  struct Case {
    double weight_decay;
    std::vector<std::vector<double>> expected;
  };
  const std::vector<Case> cases{
      {0.0,
       {{0.90000000199999997, -1.900000001, 0.5},
        {0.81969590638465184, -1.8488973939904947, 0.42558736973368988},
        {0.79862461176350807, -1.8354734342081562, 0.36167727171583935}}},
      {0.1,
       {{0.9000000016666666, -1.9000000008333333, 0.40000001999999601},
        {0.8136483454297575, -1.8336169077420748, 0.30099870785711214},
        {0.77158182105099549, -1.7944802191238758, 0.23471535423538459}}},
  };
  for (const Case& c : cases) {
    Var<double> p = Var<double>::leaf(MatrixD{{1.0, -2.0, 0.5}});
    nn::Adam<double> adam({p}, {.lr = 0.1, .weight_decay = c.weight_decay});
    for (int t = 0; t < 3; ++t) {
      adam.step({row({grads[t][0], grads[t][1], grads[t][2]})});
      expect_row(
          p.value(), c.expected[t], 1e-14,
          "weight decay " + std::to_string(c.weight_decay) + ", step " + std::to_string(t + 1));
    }
  }
}

TEST(Adam, DecoupledWeightDecayMatchesTorchAdamW) {
  // torch.optim.AdamW(lr=0.1, weight_decay=0.1) in float64 on the same gradients (PyTorch 1.13):
  // p *= 1 - lr wd before each Adam step, the moments see the gradient alone.
  const std::vector<std::vector<double>> grads{
      {0.5, -1.0, 0.0}, {0.1, 0.2, 1e-3}, {-0.3, 0.4, 2.0}};
  const std::vector<std::vector<double>> expected{
      {0.890000002, -1.880000001, 0.495},
      {0.8007959063646517, -1.8100973939804945, 0.41563736973368987},
      {0.7717166526798616, -1.778572460258351, 0.34757089801850244}};
  Var<double> p = Var<double>::leaf(MatrixD{{1.0, -2.0, 0.5}});
  nn::Adam<double> adamw({p}, {.lr = 0.1, .weight_decay = 0.1, .decoupled_weight_decay = true});
  for (int t = 0; t < 3; ++t) {
    adamw.step({row({grads[t][0], grads[t][1], grads[t][2]})});
    expect_row(p.value(), expected[t], 1e-14, "AdamW step " + std::to_string(t + 1));
  }
  expect_row(adamw.first_moment(0), {0.0195, -0.023, 0.20009}, 1e-15, "m: the gradients alone");
}

TEST(Adam, FloatFollowsDouble) {
  Var<double> pd = Var<double>::leaf(MatrixD{{1.0, -2.0}});
  Var<float> pf = Var<float>::leaf(nn::Matrix<float>{{1.0f, -2.0f}});
  nn::Adam<double> ad_double({pd}, {.lr = 0.01, .weight_decay = 1e-4});
  nn::Adam<float> ad_float({pf}, {.lr = 0.01, .weight_decay = 1e-4});
  for (int t = 0; t < 20; ++t) {
    const double g = std::sin(t);
    ad_double.step({Var<double>::leaf(MatrixD{{g, -g}}, false)});
    ad_float.step({Var<float>::leaf(nn::Matrix<float>{{float(g), float(-g)}}, false)});
  }
  EXPECT_LE((pf.value().cast<double>() - pd.value()).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(Sgd, MomentumAndNesterovMatchHandComputedValues) {
  // g = 1 every step, lr 0.1, momentum 0.9: buffers 1, 1.9, 2.71.
  Var<double> plain = Var<double>::leaf(MatrixD{{1.0}});
  Var<double> heavy = Var<double>::leaf(MatrixD{{1.0}});
  Var<double> nesterov = Var<double>::leaf(MatrixD{{1.0}});
  nn::Sgd<double> s0({plain}, {.lr = 0.1});
  nn::Sgd<double> s1({heavy}, {.lr = 0.1, .momentum = 0.9});
  nn::Sgd<double> s2({nesterov}, {.lr = 0.1, .momentum = 0.9, .nesterov = true});
  const double expected_plain[] = {0.9, 0.8, 0.7};
  const double expected_heavy[] = {0.9, 0.71, 0.439};        // p -= 0.1 b
  const double expected_nesterov[] = {0.81, 0.539, 0.1951};  // p -= 0.1 (g + 0.9 b)
  for (int t = 0; t < 3; ++t) {
    s0.step({row({1.0})});
    s1.step({row({1.0})});
    s2.step({row({1.0})});
    EXPECT_NEAR(plain.value()(0, 0), expected_plain[t], 1e-15);
    EXPECT_NEAR(heavy.value()(0, 0), expected_heavy[t], 1e-15);
    EXPECT_NEAR(nesterov.value()(0, 0), expected_nesterov[t], 1e-15);
  }
  EXPECT_NEAR(s1.momentum_buffer(0)(0, 0), 2.71, 1e-15);
}

TEST(Sgd, WeightDecayIsAddedToTheGradient) {
  Var<double> p = Var<double>::leaf(MatrixD{{2.0}});
  nn::Sgd<double> sgd({p}, {.lr = 0.5, .weight_decay = 0.1});
  sgd.step({row({0.0})});
  EXPECT_DOUBLE_EQ(p.value()(0, 0), 2.0 - 0.5 * 0.1 * 2.0);
  EXPECT_THROW(nn::Sgd<double>({p}, {.nesterov = true}), std::invalid_argument);
}

TEST(Optimizer, ChecksGradientsBeforeChangingAnything) {
  Var<double> a = Var<double>::leaf(MatrixD{{1.0, 2.0}});
  Var<double> b = Var<double>::leaf(MatrixD{{3.0}});
  nn::Adam<double> adam({a, b});
  EXPECT_THROW(adam.step({row({1.0, 1.0})}), std::invalid_argument);
  EXPECT_THROW(adam.step({row({1.0, 1.0}), row({1.0, 1.0})}), std::invalid_argument);
  EXPECT_EQ(a.value(), (MatrixD{{1.0, 2.0}}));
  EXPECT_EQ(adam.step_count(), 0);
  ad::TapeScope scope;
  EXPECT_THROW(nn::Adam<double>({a + b}), std::invalid_argument);
  EXPECT_THROW(nn::Adam<double>({a}, {.beta1 = 1.0}), std::invalid_argument);
}

TEST(Optimizer, StepsFromGradientsAccumulatedByBackward) {
  Var<double> p = Var<double>::leaf(MatrixD{{1.0, -1.0}});
  nn::Sgd<double> sgd({p}, {.lr = 0.25});
  for (int t = 0; t < 2; ++t) {
    ad::TapeScope scope;
    sgd.zero_grad();
    ad::backward(ad::sum(ad::square(p)));  // grad = 2 p
    sgd.step();
  }
  // p *= (1 - 0.25 * 2) twice.
  EXPECT_EQ(p.value(), (MatrixD{{0.25, -0.25}}));
}

TEST(Optimizer, StepAllocatesNothing) {
#if !HNN_COUNTS_ALLOCATIONS
  GTEST_SKIP() << "allocation counting needs glibc without sanitizers";
#endif
  std::mt19937_64 rng(1);
  const nn::Hnn<double> model(nn::testing::small_config(nn::ModelKind::kHnn, 2, {16, 16}), rng);
  const nn::Hnn<float> model_f = model.cast<float>();
  const MatrixD x = nn::random_normal<double>(32, 2, rng),
                y = nn::random_normal<double>(32, 2, rng);
  const auto run = [](const auto& m, auto& optimizer, const auto& xv, const auto& yv) {
    using T = typename std::decay_t<decltype(m)>::Scalar;
    for (int step = 0; step < 3; ++step) {
      ad::TapeScope scope;
      const Var<T> loss = nn::mse(m.time_derivative(Var<T>::leaf(xv)), Var<T>::constant(yv));
      const std::vector<Var<T>> grads = ad::grad<T>({loss}, optimizer.parameters());
      const long count = allocations_in([&] { optimizer.step(grads); });
      EXPECT_EQ(count, 0) << "step " << step;
    }
  };
  nn::Adam<double> adam(model.parameters(), {.weight_decay = 1e-4});
  run(model, adam, x, y);
  nn::Sgd<double> sgd(model.parameters(), {.momentum = 0.9, .weight_decay = 1e-4});
  run(model, sgd, x, y);
  nn::Adam<float> adam_f(model_f.parameters());
  run(model_f, adam_f, nn::Matrix<float>(x.cast<float>()), nn::Matrix<float>(y.cast<float>()));
  // The counter works: a matrix allocation is seen.
  EXPECT_GE(allocations_in([] {
              MatrixD m(100, 100);
              m.setZero();
            }),
            1);
}

TEST(Adam, StateRestoredIntoANewOptimizerContinuesBitForBit) {
  std::mt19937_64 rng(5);
  const MatrixD x = nn::random_normal<double>(8, 2, rng), y = nn::random_normal<double>(8, 2, rng);
  const nn::Hnn<double> a(nn::testing::small_config(nn::ModelKind::kHnn, 2, {8}), rng);
  const auto train = [&](const nn::Hnn<double>& m, nn::Adam<double>& adam, int steps) {
    for (int step = 0; step < steps; ++step) {
      ad::TapeScope scope;
      const Var<double> loss =
          nn::mse(m.time_derivative(Var<double>::leaf(x)), Var<double>::constant(y));
      adam.step(ad::grad<double>({loss}, adam.parameters()));
    }
  };
  nn::Adam<double> adam_a(a.parameters(), {.lr = 1e-2, .weight_decay = 1e-3});
  train(a, adam_a, 3);
  // A second model and optimiser from the saved values and state, then 4 more steps on each.
  const nn::Hnn<double> b = a.cast<double>();
  nn::Adam<double> adam_b(b.parameters(), adam_a.options());
  adam_b.load_state(adam_a.state());
  EXPECT_EQ(adam_b.step_count(), 3);
  train(a, adam_a, 4);
  train(b, adam_b, 4);
  for (std::size_t i = 0; i < a.parameters().size(); ++i) {
    EXPECT_EQ(a.parameters()[i].value(), b.parameters()[i].value()) << "parameter " << i;
    EXPECT_EQ(adam_a.second_moment(i), adam_b.second_moment(i)) << "parameter " << i;
  }
}

TEST(Adam, LoadStateRefusesAnotherShapeAndChangesNothing) {
  const Var<double> p = Var<double>::leaf(MatrixD::Ones(2, 3));
  nn::Adam<double> adam({p});
  nn::AdamState<double> state = adam.state();
  state.steps = 7;
  state.v[0] = MatrixD::Ones(3, 2);
  EXPECT_THROW(
      {
        try {
          adam.load_state(state);
        } catch (const std::invalid_argument& e) {
          EXPECT_STREQ(e.what(), "Adam: state moment #0 is 3x2 but its parameter is 2x3");
          throw;
        }
      },
      std::invalid_argument);
  EXPECT_EQ(adam.step_count(), 0);
  EXPECT_EQ(adam.second_moment(0), MatrixD::Zero(2, 3));
  state.v.clear();
  EXPECT_THROW(adam.load_state(state), std::invalid_argument);
  state = adam.state();
  state.steps = -1;
  EXPECT_THROW(adam.load_state(state), std::invalid_argument);
}

TEST(Adam, TwoGroupsStepAsTwoAdamsWithTheirOwnOptions) {
  // torch.optim.Adam(param_groups): each group is updated with its own options, bit for bit as
  // an Adam of its own would, and the groups share the step count.
  const auto leaf = [](const MatrixD& m) { return Var<double>::leaf(m); };
  const MatrixD a0{{1.0, -2.0}}, b0{{0.5}, {3.0}}, c0{{-1.5}};
  const Var<double> a = leaf(a0), b = leaf(b0), c = leaf(c0);
  const Var<double> a1 = leaf(a0), b1 = leaf(b0), c1 = leaf(c0);
  const nn::AdamOptions first{.lr = 0.1, .weight_decay = 0.01};
  const nn::AdamOptions second{.lr = 0.02, .beta1 = 0.8, .eps = 1e-6};
  nn::Adam<double> grouped({{{a, b}, first}, {{c}, second}});
  nn::Adam<double> alone_first({a1, b1}, first);
  nn::Adam<double> alone_second({c1}, second);
  ASSERT_EQ(grouped.group_count(), 2u);
  EXPECT_EQ(grouped.options(1).beta1, 0.8);
  ASSERT_EQ(grouped.parameters().size(), 3u);
  EXPECT_EQ(&grouped.parameters()[2].value(), &c.value());
  for (int t = 0; t < 4; ++t) {
    if (t == 2) {  // a schedule's step: one group's rate, then every group's
      grouped.set_lr(1, 0.05);
      alone_second.set_lr(0.05);
    }
    if (t == 3) {
      grouped.set_lr(0.03);
      alone_first.set_lr(0.03);
      alone_second.set_lr(0.03);
    }
    const double s = std::sin(t + 1.0);
    const Var<double> ga = row({s, -2 * s}), gb = leaf(MatrixD{{s * s}, {-s}}), gc = row({1 - s});
    grouped.step({ga, gb, gc});
    alone_first.step({ga, gb});
    alone_second.step({gc});
  }
  EXPECT_EQ(grouped.step_count(), 4);
  EXPECT_EQ(grouped.lr(), 0.03);
  EXPECT_EQ(a.value(), a1.value());
  EXPECT_EQ(b.value(), b1.value());
  EXPECT_EQ(c.value(), c1.value());
  EXPECT_EQ(grouped.second_moment(1), alone_first.second_moment(1));
  EXPECT_EQ(grouped.first_moment(2), alone_second.first_moment(0));
  // The weight decay of the first group only: the second moved as without it.
  EXPECT_NE(a.value(), a0);
}

TEST(Adam, GroupsAreCheckedNamingTheGroup) {
  const Var<double> a = Var<double>::leaf(MatrixD{{1.0}}), b = Var<double>::leaf(MatrixD{{2.0}});
  EXPECT_THROW(nn::Adam<double>(std::vector<nn::AdamGroup<double>>{}), std::invalid_argument);
  try {
    nn::Adam<double>({{{a}, {}}, {{b}, {.lr = -1}}});
    ADD_FAILURE() << "a negative learning rate was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "Adam group 1: lr must be >= 0, got -1");
  }
  // One parameter in two groups would be updated twice a step.
  EXPECT_THROW(nn::Adam<double>({{{a}, {}}, {{b, a}, {}}}), std::invalid_argument);
}

// A parameter of 2^15 elements or more is updated in blocks on the engine's threads: the same
// bits at any thread count, and no allocation after the first step (which starts the workers).
TEST(Adam, ALargeParameterStepsTheSameAtAnyThreadCountWithoutAllocating) {
  std::mt19937_64 rng(5);
  const nn::Matrix<float> start = nn::random_normal<float>(200, 200, rng);
  std::vector<nn::Matrix<float>> grads;
  for (int step = 0; step < 4; ++step) grads.push_back(nn::random_normal<float>(200, 200, rng));
  const auto run = [&](int threads) {
    ad::set_num_threads(threads);
    const Var<float> p = Var<float>::leaf(start);
    nn::Adam<float> adam({p}, {.lr = 1e-2, .weight_decay = 1e-3});
    for (const nn::Matrix<float>& g : grads) {
      const std::vector<Var<float>> step_grads{Var<float>::constant(g)};
      const long count = allocations_in([&] { adam.step(step_grads); });
#if HNN_COUNTS_ALLOCATIONS
      if (adam.step_count() > 1) {
        EXPECT_EQ(count, 0) << threads << " thread(s)";
      }
#endif
      (void)count;
    }
    ad::set_num_threads(2);
    return nn::Matrix<float>(p.value());
  };
  const nn::Matrix<float> one = run(1);
  EXPECT_NE(one, start);
  for (int threads : {2, 3}) EXPECT_EQ(run(threads), one) << threads << " threads";
}
