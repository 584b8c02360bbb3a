// ExpressionSystem: the field and H against the hand-written systems and finite differences,
// energy along rollouts, separability and the splitting methods' refusal, every bad input.
#include "physics/expression_system.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <functional>

#include "physics/integrator.h"
#include "physics/oscillators.h"
#include "physics/simulate.h"
#include "physics_test_util.h"

namespace hnn::physics {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

const char* const kPendulum = "p^2/2 + 9.81*(1 - cos(q))";
const char* const kHenonHeiles = "(px^2+py^2)/2 + (x^2+y^2)/2 + x^2*y - y^3/3";
const char* const kNonSeparable = "(q^2 + 1)*(p^2 + 1)/2";

StateSampling in_box(std::vector<std::pair<std::string, ValueRange>> ranges) {
  StateSampling s;
  s.ranges = std::move(ranges);
  return s;
}

StateSampling in_band(double lo, double hi, StateSampling s = {}) {
  s.energy = ValueRange{lo, hi};
  return s;
}

ExpressionSystem one_dof(const std::string& h, StateSampling sampling = {}) {
  return ExpressionSystem(h, {"q"}, {"p"}, std::move(sampling));
}

ExpressionSystem henon_heiles(StateSampling sampling = {}) {
  return ExpressionSystem(kHenonHeiles, {"x", "y"}, {"px", "py"}, std::move(sampling));
}

Batch uniform_states(int rows, int cols, double half_width, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-half_width, half_width);
  Batch x(rows, cols);
  for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] = u(rng);
  return x;
}

Batch field_of(const System& system, const Batch& x) {
  Batch dxdt;
  system.vector_field(x, dxdt);
  return dxdt;
}

// The message of the std::invalid_argument that f throws ("" if it throws nothing).
std::string invalid_argument_message(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(ExpressionSystem, SameHamiltonianAsPendulumAndSpringGivesTheSameFieldAndEnergy) {
  const Batch x = uniform_states(300, 2, 3.0, 1);
  const Pendulum pendulum;  // 3(1 - cos q) + p^2
  const ExpressionSystem as_pendulum = one_dof("3*(1 - cos(q)) + p^2");
  EXPECT_LT((field_of(as_pendulum, x) - field_of(pendulum, x)).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((as_pendulum.energy_batch(x) - pendulum.energy_batch(x)).cwiseAbs().maxCoeff(), 1e-14);
  const Spring spring;  // q^2 + p^2
  const ExpressionSystem as_spring = one_dof("q^2 + p^2");
  EXPECT_LT((field_of(as_spring, x) - field_of(spring, x)).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((as_spring.energy_batch(x) - spring.energy_batch(x)).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(ExpressionSystem, FieldMatchesFiniteDifferencesOfH) {
  const std::vector<ExpressionSystem> systems = {
      one_dof(kPendulum), one_dof(kNonSeparable), henon_heiles(),
      one_dof("exp(q/3)*sqrt(p^2 + 2) + atan2(q, 2 + p^2) + tanh(q*p) + abs(q)^3 - 1/(q^2 + 1)"),
      one_dof("log(q^2 + 1)*sinh(p/2) + cosh(q)^(3/2) + Pi*p^4/7 - 2^q")};
  for (const ExpressionSystem& s : systems) {
    const Batch x = uniform_states(50, s.dim(), 1.5, 2);
    const Batch fd = testing::symplectic_gradient_fd(s, x);
    const Batch exact = field_of(s, x);
    EXPECT_LT((exact - fd).cwiseAbs().maxCoeff() / (1.0 + exact.cwiseAbs().maxCoeff()), 1e-8)
        << s.name();
  }
}

TEST(ExpressionSystem, HenonHeilesFieldIsTheTextbookOne) {
  const ExpressionSystem hh = henon_heiles();
  const Batch x = uniform_states(40, 4, 1.0, 3);
  Batch want(x.rows(), 4);
  const auto qx = x.col(0).array(), qy = x.col(1).array();
  want.col(0) = x.col(2);
  want.col(1) = x.col(3);
  want.col(2) = -(qx + 2.0 * qx * qy);
  want.col(3) = -(qy + qx.square() - qy.square());
  EXPECT_LT((field_of(hh, x) - want).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_EQ(hh.variables(), (std::vector<std::string>{"x", "y", "px", "py"}));
  EXPECT_EQ(hh.derivative_text(2), "px");  // dH/dpx
}

// max over rows and times of |H(x(t)) - H(x(0))| / |H(x(0))| along a dopri5 rollout.
double dopri5_energy_error(const ExpressionSystem& s, const Batch& x0, const char* method) {
  const auto integrator = make_integrator(method, {.dt = 1e-2, .rtol = 1e-11, .atol = 1e-13});
  const Trajectory path = integrate_system(*integrator, s, x0, linspace(0.0, 10.0, 21));
  return testing::max_in(testing::relative_energy_errors(s, path), 0, path.t.size());
}

TEST(ExpressionSystem, Dopri5RolloutsConserveH) {
  std::mt19937_64 rng(4);
  const ExpressionSystem pendulum = one_dof(kPendulum);
  EXPECT_LT(dopri5_energy_error(pendulum, pendulum.sample_initial_states(20, rng), "dopri5"), 1e-8);
  // Bounded orbits of Henon-Heiles lie below the escape energy 1/6.
  const ValueRange small{-0.4, 0.4};
  const ExpressionSystem hh = henon_heiles(
      in_band(0.05, 0.12, in_box({{"x", small}, {"y", small}, {"px", small}, {"py", small}})));
  EXPECT_LT(dopri5_energy_error(hh, hh.sample_initial_states(20, rng), "dopri5"), 1e-8);
  const ExpressionSystem coupled = one_dof(kNonSeparable);
  const Batch x0 = coupled.sample_initial_states(20, rng);
  EXPECT_LT(dopri5_energy_error(coupled, x0, "dopri5"), 1e-8);
  // Symplectic: an O(dt^2) error that stays bounded, no drift.
  EXPECT_LT(dopri5_energy_error(coupled, x0, "midpoint"), 1e-4);
}

TEST(ExpressionSystem, SeparabilityIsDecidedSymbolically) {
  EXPECT_TRUE(one_dof(kPendulum).separable());
  EXPECT_TRUE(henon_heiles().separable());
  EXPECT_FALSE(one_dof(kNonSeparable).separable());
  EXPECT_FALSE(one_dof("q*p + p^2").separable());
  EXPECT_TRUE(one_dof("(q + p)^2 - 2*q*p").separable());  // q^2 + p^2 once expanded
  EXPECT_TRUE(one_dof("q^2").separable());
}

TEST(ExpressionSystem, SplittingMethodsUseTheExactHalvesOrRefuse) {
  const Batch x0 = uniform_states(8, 2, 1.0, 5);
  const auto leapfrog = make_integrator("leapfrog", {.dt = 1e-2});
  const Batch by_expression =
      integrate_system(*leapfrog, one_dof("3*(1 - cos(q)) + p^2"), x0, {0.0, 2.0}).states.back();
  const Batch by_hand = integrate_system(*leapfrog, Pendulum(), x0, {0.0, 2.0}).states.back();
  EXPECT_LT((by_expression - by_hand).cwiseAbs().maxCoeff(), 1e-12);

  const ExpressionSystem coupled = one_dof(kNonSeparable);
  for (const char* method : {"leapfrog", "yoshida4", "symplectic_euler"}) {
    const std::string message = invalid_argument_message([&] {
      integrate_system(*make_integrator(method), coupled, x0, {0.0, 1.0});
    });
    EXPECT_THAT(message,
                AllOf(HasSubstr(method), HasSubstr("separable"), HasSubstr("(q^2 + 1)*(p^2 + 1)/2"),
                      HasSubstr("midpoint"), HasSubstr("rk4"), HasSubstr("dopri5")));
  }
}

TEST(ExpressionSystem, SamplesFromTheBoxOrTheEnergyBandDeterministically) {
  const ExpressionSystem boxed = one_dof(kPendulum, in_box({{"q", {2.0, 3.0}}}));
  std::mt19937_64 a(6), b(6);
  const Batch x = boxed.sample_initial_states(100, a);
  EXPECT_EQ(x, boxed.sample_initial_states(100, b));
  EXPECT_GE(x.col(0).minCoeff(), 2.0);
  EXPECT_LE(x.col(0).maxCoeff(), 3.0);
  EXPECT_GE(x.col(1).minCoeff(), -1.0);  // unnamed: [-1, 1]
  EXPECT_LE(x.col(1).maxCoeff(), 1.0);
  const ExpressionSystem band = one_dof(kPendulum, in_band(1.0, 2.0));
  const Eigen::VectorXd h = band.hamiltonian_batch(band.sample_initial_states(100, a));
  EXPECT_GE(h.minCoeff(), 1.0);
  EXPECT_LE(h.maxCoeff(), 2.0);
}

TEST(ExpressionSystem, BadExpressionsAndNamesSayWhatIsWrong) {
  const auto message = [](const std::string& h, std::vector<std::string> q,
                          std::vector<std::string> p) {
    return invalid_argument_message([&] { ExpressionSystem(h, q, p); });
  };
  EXPECT_THAT(message("p^2/2 +", {"q"}, {"p"}),
              AllOf(HasSubstr("'p^2/2 +' does not parse"), HasSubstr("unexpected token")));
  EXPECT_THAT(message("p^2/2 + foo(q)", {"q"}, {"p"}), HasSubstr("no function \"foo\""));
  EXPECT_THAT(message("p^2/2 + r*q", {"q"}, {"p"}),
              AllOf(HasSubstr("unknown name 'r'"), HasSubstr("coordinates: q; momenta: p")));
  EXPECT_THAT(message("x + y + px", {"x", "y"}, {"px"}),
              AllOf(HasSubstr("2 coordinates (x, y) and 1 momenta (px)")));
  EXPECT_THAT(message("p", {}, {}), HasSubstr("0 coordinates"));
  EXPECT_THAT(message("q^2", {"q"}, {"q"}), HasSubstr("the name 'q' is given twice"));
  EXPECT_THAT(message("cos^2 + p^2", {"cos"}, {"p"}),
              HasSubstr("coordinate name 'cos' is a function or constant"));
  EXPECT_THAT(message("q + Pi", {"q"}, {"Pi"}), HasSubstr("momentum name 'Pi' is a function"));
  EXPECT_THAT(message("q + p", {"1q"}, {"p"}), HasSubstr("name '1q' is not a name"));
  EXPECT_THAT(message("I*q + p^2", {"q"}, {"p"}), HasSubstr("H must be real"));
  EXPECT_THAT(message("zeta(q) + p^2", {"q"}, {"p"}),
              AllOf(HasSubstr("H = zeta(q) + p^2: cannot evaluate"), HasSubstr("'zeta'")));
  EXPECT_THAT(message("csgn(q) + p^2", {"q"}, {"p"}), HasSubstr("no closed-form derivative"));
}

TEST(ExpressionSystem, NonFiniteValuesNameTheState) {
  const ExpressionSystem s = one_dof("log(q) + p^2/2");
  Batch x(2, 2);
  x << 1.0, 0.5, -1.0, 0.25;
  EXPECT_THAT(invalid_argument_message([&] { s.hamiltonian_batch(x); }),
              HasSubstr("H = log(q) + p^2/2: H is NaN at state 1 (q = -1, p = 0.25)"));
  x(1, 0) = 0.0;
  EXPECT_THAT(invalid_argument_message([&] { field_of(s, x); }),
              HasSubstr("-dH/dq is -inf at state 1 (q = 0, p = 0.25)"));
  EXPECT_THAT(invalid_argument_message([&] { field_of(s, Batch::Zero(1, 3)); }),
              HasSubstr("state has 3 columns, expected 2 (q, p)"));
}

TEST(ExpressionSystem, BadSamplingSaysWhatIsWrong) {
  const auto message = [](StateSampling sampling) {
    return invalid_argument_message([&] {
      std::mt19937_64 rng(7);
      one_dof(kPendulum, sampling).sample_initial_states(10, rng);
    });
  };
  EXPECT_THAT(message(in_box({{"r", {0.0, 1.0}}})),
              HasSubstr("sampling range for 'r', which is not a coordinate or momentum (q, p)"));
  EXPECT_THAT(message(in_box({{"q", {1.0, 1.0}}})), HasSubstr("it needs finite lo < hi"));
  EXPECT_THAT(message(in_band(2.0, 1.0)), HasSubstr("needs finite LO <= HI"));
  StateSampling hopeless = in_band(100.0, 200.0);
  hopeless.max_draws = 5000;
  EXPECT_THAT(message(hopeless),
              HasSubstr("only 0 of 10 states with H in [100, 200] after 5120 draws"));
}

// Field evaluations of a 1000-state batch per second, the expression beside the hand-written
// pendulum (printed; the shared machine makes only the ratio meaningful).
TEST(ExpressionSystem, MeasuresFieldSpeedAgainstThePendulum) {
  const Batch x = uniform_states(1000, 2, 2.0, 8);
  const auto rate = [&](const System& s) {
    Batch dxdt;
    int calls = 0;
    const auto start = std::chrono::steady_clock::now();
    double seconds = 0.0;
    while (seconds < 0.2) {
      s.vector_field(x, dxdt);
      ++calls;
      seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return calls / seconds;
  };
  const double expression = rate(one_dof("3*(1 - cos(q)) + p^2")), hand = rate(Pendulum());
  std::printf("field on 1000 states: expression %.0f/s, Pendulum %.0f/s (ratio %.2f)\n", expression,
              hand, hand / expression);
  EXPECT_GT(expression, 0.0);
}

}  // namespace
}  // namespace hnn::physics
