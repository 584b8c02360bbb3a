// AutodiffSystem (hnn::physics_autodiff): H written with the engine's ops gives the exact field of
// known systems and the same field as ExpressionSystem, conserves energy under DOPRI5, samples
// as told, keeps the caller's tape and grad mode, and rejects bad input by name.
#include "physics/autodiff/autodiff_system.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "autodiff/ops.h"
#include "autodiff/tape.h"
#include "physics/expression_system.h"
#include "physics/integrator.h"
#include "physics/oscillators.h"
#include "physics_test_util.h"

namespace hnn::physics {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using V = ad::Var<double>;

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

double max_abs(const Batch& a) { return a.cwiseAbs().maxCoeff(); }

// The message of the std::invalid_argument that f throws ("" if it throws nothing).
std::string invalid_argument_message(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// H = (px^2 + py^2)/2 + (x^2 + y^2)/2 + x^2 y - y^3/3, q = (x, y), p = (px, py).
V henon_heiles_h(const V& q, const V& p) {
  const V x = ad::slice_cols(q, 0, 1), y = ad::slice_cols(q, 1, 1);
  return 0.5 * ad::sum_cols(ad::square(p) + ad::square(q)) + ad::square(x) * y -
         ad::square(y) * y / 3.0;
}

AutodiffSystem henon_heiles(BoxSampling sampling = {}) {
  return AutodiffSystem("henon-heiles", 2, henon_heiles_h, std::move(sampling));
}

// Inside the triangle where the motion stays bounded: |x|, |y| < 0.5 and E in [0.02, 0.12].
BoxSampling bounded_band() {
  BoxSampling s;
  s.box.assign(4, ValueRange{-0.5, 0.5});
  s.energy = ValueRange{0.02, 0.12};
  return s;
}

TEST(AutodiffSystem, SpringAndPendulumMatchTheHandWrittenSystems) {
  const Batch x = uniform_states(300, 2, 3.0, 1);
  const Spring spring;  // q^2 + p^2
  const AutodiffSystem as_spring(
      "spring", 1, [](const V& q, const V& p) { return ad::square(q) + ad::square(p); });
  EXPECT_LT(max_abs(field_of(as_spring, x) - field_of(spring, x)), 1e-14);
  EXPECT_LT((as_spring.energy_batch(x) - spring.energy_batch(x)).cwiseAbs().maxCoeff(), 1e-14);

  const Pendulum pendulum;  // 3(1 - cos q) + p^2
  const AutodiffSystem as_pendulum("pendulum", 1, [](const V& q, const V& p) {
    return 3.0 * (1.0 - ad::cos(q)) + ad::square(p);
  });
  EXPECT_LT(max_abs(field_of(as_pendulum, x) - field_of(pendulum, x)), 1e-14);
  EXPECT_LT((as_pendulum.energy_batch(x) - pendulum.energy_batch(x)).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_EQ(as_pendulum.dim(), 2);
  EXPECT_EQ(as_pendulum.n_dof(), 1);
  EXPECT_EQ(as_pendulum.name(), "pendulum");
}

TEST(AutodiffSystem, HenonHeilesMatchesItsAnalyticField) {
  const Batch s = uniform_states(500, 4, 1.5, 2);
  const AutodiffSystem system = henon_heiles();
  Batch expected(s.rows(), 4);
  const auto x = s.col(0).array(), y = s.col(1).array();
  expected.col(0) = s.col(2);
  expected.col(1) = s.col(3);
  expected.col(2) = -(x + 2.0 * x * y);
  expected.col(3) = -(y + x.square() - y.square());
  EXPECT_LT(max_abs(field_of(system, s) - expected), 1e-14);
  const Eigen::ArrayXd h = 0.5 * (s.col(2).array().square() + s.col(3).array().square()) +
                           0.5 * (x.square() + y.square()) + x.square() * y - y.cube() / 3.0;
  EXPECT_LT((system.hamiltonian_batch(s).array() - h).abs().maxCoeff(), 1e-14);
  // gradient() is dH/dx, the field before the symplectic turn.
  const Batch dh = system.gradient(s);
  EXPECT_LT(max_abs(dh.leftCols(2) + expected.rightCols(2)), 1e-14);
  EXPECT_LT(max_abs(dh.rightCols(2) - expected.leftCols(2)), 1e-14);
}

TEST(AutodiffSystem, SameFieldAsExpressionSystemForTheSameHamiltonian) {
  const ExpressionSystem expression("(px^2+py^2)/2 + (x^2+y^2)/2 + x^2*y - y^3/3", {"x", "y"},
                                    {"px", "py"});
  const AutodiffSystem system = henon_heiles();
  const Batch s = uniform_states(400, 4, 2.0, 3);
  EXPECT_LT(max_abs(field_of(system, s) - field_of(expression, s)), 1e-13);
  EXPECT_LT((system.hamiltonian_batch(s) - expression.hamiltonian_batch(s)).cwiseAbs().maxCoeff(),
            1e-13);

  // Three degrees of freedom with cross terms and transcendental functions.
  const ExpressionSystem coupled("(a^2 + b^2 + c^2)/2 + exp(-x*y) + sin(y + z)*a + x^2*z^2",
                                 {"x", "y", "z"}, {"a", "b", "c"});
  const AutodiffSystem coupled_ad("coupled", 3, [](const V& q, const V& p) {
    const V x = ad::slice_cols(q, 0, 1), y = ad::slice_cols(q, 1, 1), z = ad::slice_cols(q, 2, 1);
    const V a = ad::slice_cols(p, 0, 1);
    return 0.5 * ad::sum_cols(ad::square(p)) + ad::exp(-(x * y)) + ad::sin(y + z) * a +
           ad::square(x) * ad::square(z);
  });
  const Batch s3 = uniform_states(400, 6, 1.5, 4);
  EXPECT_LT(max_abs(field_of(coupled_ad, s3) - field_of(coupled, s3)), 1e-13);
  EXPECT_LT(max_abs(field_of(coupled_ad, s3) - testing::symplectic_gradient_fd(coupled_ad, s3)),
            1e-7);
}

TEST(AutodiffSystem, EnergyIsConservedAlongDopri5) {
  const AutodiffSystem system = henon_heiles(bounded_band());
  std::mt19937_64 rng(5);
  const Batch x0 = system.sample_initial_states(16, rng);
  const auto integrator = make_integrator("dopri5", {.rtol = 1e-10, .atol = 1e-12});
  const Trajectory trajectory = integrator->integrate(system.field(), x0, linspace(0, 50, 101));
  const std::vector<double> errors = testing::relative_energy_errors(system, trajectory);
  EXPECT_LT(testing::max_in(errors, 0, errors.size()), 1e-8);
  // Bounded: the motion stays in the well (|q| < 1) below the escape energy 1/6.
  for (const Batch& x : trajectory.states) EXPECT_LT(x.leftCols(2).cwiseAbs().maxCoeff(), 1.0);
}

TEST(AutodiffSystem, SamplesFromTheBoxTheEnergyBandOrItsOwnSampler) {
  const AutodiffSystem system = henon_heiles(bounded_band());
  std::mt19937_64 rng(6), again(6);
  const Batch x = system.sample_initial_states(200, rng);
  ASSERT_EQ(x.rows(), 200);
  ASSERT_EQ(x.cols(), 4);
  EXPECT_LE(x.cwiseAbs().maxCoeff(), 0.5);
  const Eigen::VectorXd h = system.hamiltonian_batch(x);
  EXPECT_GE(h.minCoeff(), 0.02);
  EXPECT_LE(h.maxCoeff(), 0.12);
  EXPECT_EQ(system.sample_initial_states(200, again), x);  // deterministic in rng

  const AutodiffSystem box = henon_heiles();  // no box given: [-1, 1] per column
  const Batch wide = box.sample_initial_states(500, rng);
  EXPECT_LE(wide.cwiseAbs().maxCoeff(), 1.0);
  EXPECT_GT(wide.cwiseAbs().maxCoeff(), 0.9);

  const AutodiffSystem own("own-sampler", 2, henon_heiles_h, [](int n, std::mt19937_64&) {
    return Batch(Batch::Constant(n, 4, 0.25));
  });
  EXPECT_EQ(own.sample_initial_states(3, rng), Batch(Batch::Constant(3, 4, 0.25)));

  BoxSampling impossible = bounded_band();
  impossible.energy = ValueRange{5.0, 6.0};  // above anything the box reaches
  impossible.max_draws = 10'000;
  EXPECT_THAT(
      invalid_argument_message([&] { henon_heiles(impossible).sample_initial_states(5, rng); }),
      AllOf(HasSubstr("henon-heiles"), HasSubstr("only 0 of 5")));
}

TEST(AutodiffSystem, KeepsTheCallersTapeAndGradMode) {
  const AutodiffSystem system = henon_heiles();
  const Batch s = uniform_states(20, 4, 1.0, 7);
  const Batch expected = field_of(system, s);
  const std::size_t before = ad::Tape<double>::current().size();
  {
    ad::NoGradGuard values_only;  // a rollout's evaluation: the field still differentiates
    EXPECT_EQ(field_of(system, s), expected);
    EXPECT_FALSE(ad::grad_enabled());
  }
  EXPECT_TRUE(ad::grad_enabled());
  system.hamiltonian_batch(s);
  EXPECT_EQ(ad::Tape<double>::current().size(), before);  // everything recorded was released
}

TEST(AutodiffSystem, HamiltoniansThatIgnoreAVariableGiveZeros) {
  const AutodiffSystem free_particle("free", 1,
                                     [](const V&, const V& p) { return 0.5 * ad::square(p); });
  const Batch s = uniform_states(10, 2, 1.0, 8);
  const Batch f = field_of(free_particle, s);
  EXPECT_EQ(f.col(0), s.col(1));
  EXPECT_EQ(max_abs(f.col(1)), 0.0);

  const AutodiffSystem constant("constant", 2, [](const V& q, const V&) {
    return V::constant(ad::Matrix<double>::Constant(q.rows(), 1, 2.0));
  });
  EXPECT_EQ(max_abs(field_of(constant, uniform_states(5, 4, 1.0, 9))), 0.0);
  EXPECT_EQ(field_of(constant, Batch(0, 4)).rows(), 0);
  EXPECT_EQ(constant.hamiltonian_batch(Batch(0, 4)).size(), 0);
}

TEST(AutodiffSystem, BadInputThrowsNamingWhatIsWrong) {
  const auto h = henon_heiles_h;
  EXPECT_THAT(invalid_argument_message([&] { AutodiffSystem("hh", 0, h); }),
              AllOf(HasSubstr("hh"), HasSubstr("0 degrees of freedom")));
  EXPECT_THAT(invalid_argument_message([&] { AutodiffSystem("", 2, h); }), HasSubstr("name"));
  EXPECT_THAT(invalid_argument_message([&] { AutodiffSystem("hh", 2, AutodiffHamiltonian{}); }),
              HasSubstr("callable is empty"));
  EXPECT_THAT(invalid_argument_message([&] { AutodiffSystem("hh", 2, h, StateSampler{}); }),
              HasSubstr("sampler is empty"));

  // Wrong shapes from H, found by the probe at construction.
  EXPECT_THAT(invalid_argument_message([] {
                AutodiffSystem("summed", 1, [](const V& q, const V& p) {
                  return ad::sum(ad::square(q) + ad::square(p));
                });
              }),
              AllOf(HasSubstr("summed"), HasSubstr("returned 1x1"), HasSubstr("2x1"),
                    HasSubstr("summed over the batch")));
  EXPECT_THAT(invalid_argument_message([] {
                AutodiffSystem("per-column", 2, [](const V& q, const V& p) {
                  return ad::square(q) + ad::square(p);
                });
              }),
              AllOf(HasSubstr("per-column"), HasSubstr("returned 2x2")));
  EXPECT_THAT(invalid_argument_message(
                  [] { AutodiffSystem("undefined", 1, [](const V&, const V&) { return V(); }); }),
              AllOf(HasSubstr("undefined"), HasSubstr("undefined Var")));
  EXPECT_THAT(invalid_argument_message([] {
                AutodiffSystem("engine-error", 1, [](const V& q, const V& p) {
                  return ad::matmul(q, p);  // 2x1 by 2x1
                });
              }),
              AllOf(HasSubstr("engine-error"), HasSubstr("H(q, p) failed"), HasSubstr("matmul")));

  // Wrong shapes at a call: a callable whose shape depends on the batch.
  const AutodiffSystem first_rows("first-rows", 1, [](const V& q, const V& p) {
    return q.rows() <= 2 ? ad::square(q) + ad::square(p)
                         : ad::sum_cols(ad::transpose(ad::slice_cols(ad::transpose(q), 0, 2)));
  });
  EXPECT_THAT(invalid_argument_message([&] { field_of(first_rows, uniform_states(5, 2, 1, 1)); }),
              AllOf(HasSubstr("first-rows"), HasSubstr("for q and p of 5x1"), HasSubstr("5x1")));

  // Bad batches and sampling.
  const AutodiffSystem system = henon_heiles();
  EXPECT_THAT(invalid_argument_message([&] { field_of(system, Batch(3, 3)); }),
              AllOf(HasSubstr("henon-heiles"), HasSubstr("3 columns"), HasSubstr("4")));
  EXPECT_THAT(invalid_argument_message([&] { system.hamiltonian_batch(Batch(3, 5)); }),
              HasSubstr("5 columns"));
  std::mt19937_64 rng(10);
  EXPECT_THAT(invalid_argument_message([&] { system.sample_initial_states(-1, rng); }),
              HasSubstr("cannot sample -1"));
  EXPECT_THAT(invalid_argument_message([&] {
                henon_heiles({.box = {{-1, 1}}});
              }),
              AllOf(HasSubstr("box of 1 ranges"), HasSubstr("4")));
  EXPECT_THAT(invalid_argument_message([&] {
                henon_heiles({.box = {{-1, 1}, {1, -1}, {-1, 1}, {-1, 1}}});
              }),
              HasSubstr("column 1 is 1:-1"));
  EXPECT_THAT(invalid_argument_message([&] {
                henon_heiles({.energy = ValueRange{1, 0}});
              }),
              HasSubstr("energy band 1:0"));
  const AutodiffSystem bad_sampler("bad-sampler", 2, h,
                                   [](int n, std::mt19937_64&) { return Batch(n, 3); });
  EXPECT_THAT(invalid_argument_message([&] { bad_sampler.sample_initial_states(4, rng); }),
              AllOf(HasSubstr("bad-sampler"), HasSubstr("returned 4x3"), HasSubstr("4x4")));

  // Non-finite H or field, naming the state.
  const AutodiffSystem log_h("log", 1,
                             [](const V& q, const V& p) { return ad::log(q) + ad::square(p); });
  Batch at_zero(2, 2);
  at_zero << 1.0, 0.5, 0.0, 0.5;
  EXPECT_THAT(invalid_argument_message([&] { log_h.hamiltonian_batch(at_zero); }),
              AllOf(HasSubstr("log: H is -inf at state 1"), HasSubstr("(q_1 = 0, p_1 = 0.5)")));
  EXPECT_THAT(invalid_argument_message([&] { field_of(log_h, at_zero); }),
              AllOf(HasSubstr("log: the field is"), HasSubstr("at state 1")));
}

}  // namespace
}  // namespace hnn::physics
